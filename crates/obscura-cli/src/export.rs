//! `obscura export`: any scene (a file, a scene file, a demo such as the demo level) as
//! a Wavefront OBJ whose `f` lines are the scene's faces in id order, so that the face
//! ids of a picture of the OBJ are the scene's.
//!
//! One `o` statement per object (its name), its vertices in world space (the object's
//! transform applied, as the pipeline applies it), then one `f` line per face id of
//! the object:
//! - a face kept as one convex polygon is written as that polygon;
//! - a face the loader cut into several polygons (a concave or non-planar face) is
//!   written as the outline of its polygons (the loader cuts it again); when its
//!   polygons do not make one outline (slivers dropped by the triangulation), its
//!   largest polygon is written and the run says how many faces were so simplified;
//! - a face the loader dropped (degenerate) is written as a degenerate triangle, which
//!   the loader drops again: the id is kept, nothing is drawn.
//!
//! Polygons of mirrored objects (negative determinant) are written reversed, so that
//! their front stays their front in world space. Colours and materials are not
//! written.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use obscura::{Error, Result, Scene};

use crate::common::ViewArgs;
use crate::out::{errln, outln};
use crate::outputs::{OutputArgs, Outputs};

pub const EXAMPLES: &str = "\
Examples:
  obscura export demo:city -o city.obj
  obscura export scene.toml -o scene.obj
  obscura render city.obj --ids ids.npy     # the same face ids as demo:city";

#[derive(Args, Debug)]
pub struct ExportArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// The OBJ to write (never one of the files the scene is read from).
    #[arg(short = 'o', long = "output", value_name = "OUT.obj")]
    pub output: PathBuf,
    #[command(flatten)]
    pub naming: OutputArgs,
}

pub fn run(args: &ExportArgs) -> Result<()> {
    let mut outputs = Outputs::stage_with_extensions(
        args.view.scene.as_deref(),
        &[("-o", Some(&args.output))],
        args.naming,
        &[("-o", "obj", "Wavefront OBJ")],
    )?;
    let loaded = args.view.load()?;
    outputs.check_inputs(loaded.scene.source_files())?;
    let (text, simplified) = obj_text(&loaded.scene, &loaded.spec);
    outputs.write("-o", |p| write_text(p, &text))?;
    outputs.commit()?;
    if simplified > 0 {
        errln!(
            "warning: {simplified} face(s) cut into pieces that make no single outline were \
             written as their largest piece"
        );
    }
    outln!(
        "wrote {} ({} objects, {} faces)",
        args.output.display(),
        loaded.scene.objects().len(),
        loaded.scene.face_count()
    );
    Ok(())
}

fn write_text(p: &Path, text: &str) -> Result<()> {
    std::fs::write(p, text).map_err(|e| Error::io(p, e))
}

/// The OBJ text of a scene and how many faces were simplified (see the
/// [module documentation](self)).
pub fn obj_text(scene: &Scene, spec: &str) -> (String, usize) {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {spec} exported by obscura {}: {} objects, {} faces in id order",
        env!("CARGO_PKG_VERSION"),
        scene.objects().len(),
        scene.face_count()
    );
    let mut base = 1usize;
    let mut simplified = 0;
    for o in scene.objects() {
        let mesh = &o.mesh;
        if mesh.face_count() == 0 {
            continue;
        }
        let name: String = o
            .name
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
        let name = if name.trim().is_empty() {
            "object".to_string()
        } else {
            name
        };
        let _ = writeln!(s, "o {}", name.trim());
        let positions = mesh.positions();
        for p in positions {
            let w = o.transform.transform_point3(*p);
            let _ = writeln!(s, "v {} {} {}", w.x, w.y, w.z);
        }
        // A vertex for the degenerate stand-ins of dropped faces when the mesh has none.
        let spare = if positions.is_empty() {
            let _ = writeln!(s, "v 0 0 0");
            1
        } else {
            0
        };
        for f in 0..mesh.face_count() {
            let polys = mesh.polygons_of_face(f);
            let mut loop_: Vec<u32> = match polys.len() {
                0 => vec![0, 0, 0],
                1 => mesh.polygon(polys.start).to_vec(),
                _ => {
                    let parts: Vec<&[u32]> = polys.clone().map(|p| mesh.polygon(p)).collect();
                    outline(&parts).unwrap_or_else(|| {
                        simplified += 1;
                        parts
                            .iter()
                            .max_by_key(|p| p.len())
                            .map(|p| p.to_vec())
                            .unwrap_or_default()
                    })
                }
            };
            if o.mirrored {
                loop_.reverse();
            }
            s.push('f');
            for v in loop_ {
                let _ = write!(s, " {}", base + v as usize);
            }
            s.push('\n');
        }
        base += positions.len() + spare;
    }
    (s, simplified)
}

/// The outline of polygons that tile one face: the directed edges whose reverse is
/// not among them, chained into one loop; `None` when they make no single loop.
fn outline(parts: &[&[u32]]) -> Option<Vec<u32>> {
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    for p in parts {
        for i in 0..p.len() {
            *edges.entry((p[i], p[(i + 1) % p.len()])).or_default() += 1;
        }
    }
    let boundary: Vec<(u32, u32)> = edges
        .keys()
        .copied()
        .filter(|&(a, b)| !edges.contains_key(&(b, a)))
        .collect();
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(a, b) in &boundary {
        if next.insert(a, b).is_some() {
            return None;
        }
    }
    // Start from the first vertex of the first polygon that is on the outline, so the
    // outline starts where the face did.
    let start = parts
        .iter()
        .flat_map(|p| p.iter())
        .copied()
        .find(|v| next.contains_key(v))?;
    let mut out = vec![start];
    let mut v = start;
    while let Some(&n) = next.get(&v) {
        if n == start {
            break;
        }
        if out.len() > boundary.len() {
            return None;
        }
        out.push(n);
        v = n;
    }
    (out.len() == boundary.len() && out.len() >= 3).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outline_of_a_fan_is_the_polygon() {
        // A square cut into two triangles along 0-2.
        let o = outline(&[&[0, 1, 2], &[0, 2, 3]]).unwrap();
        assert_eq!(o, [0, 1, 2, 3]);
        // Two triangles that share nothing make two loops.
        assert!(outline(&[&[0, 1, 2], &[3, 4, 5]]).is_none());
    }
}
