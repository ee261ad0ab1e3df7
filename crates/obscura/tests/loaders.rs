//! Every scene loader on small files written here: counts, face id order, colours,
//! transforms, binary and ASCII variants, and each kind of bad input with the file and
//! line (or element) its error must name.
// The loaders: built with every file format (the default features).
#![cfg(all(
    feature = "obj",
    feature = "gltf",
    feature = "stl",
    feature = "ply",
    feature = "toml-scene"
))]

use std::path::Path;
use std::sync::Arc;

mod common;

use common::TempDir;
use glam::DVec3;
use obscura::geom::Aabb;
use obscura::scene::load::load_file;
use obscura::{Error, Projection, Scene};

// ---------------------------------------------------------------------------------
// Helpers

fn load(path: &Path) -> Scene {
    load_file(path).unwrap_or_else(|e| panic!("{} should load: {e}", path.display()))
}

fn load_err(path: &Path) -> Error {
    match load_file(path) {
        Ok(s) => panic!(
            "{} should fail, loaded {} faces",
            path.display(),
            s.face_count()
        ),
        Err(e) => e,
    }
}

/// Asserts that an error is a parse error at `path:line` whose message has `needle`.
fn assert_at_line(e: &Error, path: &Path, line: usize, needle: &str) {
    let text = e.to_string();
    assert!(
        matches!(e, Error::Parse { .. }),
        "expected a parse error, got {e:?}"
    );
    let at = format!("{}:{line}:", path.display());
    assert!(text.starts_with(&at), "\"{text}\" should start with {at}");
    assert!(
        text.to_lowercase().contains(&needle.to_lowercase()),
        "\"{text}\" should mention \"{needle}\""
    );
}

/// Asserts that an error is a format error on `path` naming `element`, with `needle`.
fn assert_element(e: &Error, path: &Path, element: &str, needle: &str) {
    let text = e.to_string();
    assert!(
        matches!(e, Error::Format { .. }),
        "expected a format error, got {e:?}"
    );
    assert!(
        text.starts_with(&format!("{}: ", path.display())),
        "\"{text}\" should name {}",
        path.display()
    );
    assert!(text.contains(element), "\"{text}\" should name {element}");
    assert!(
        text.to_lowercase().contains(&needle.to_lowercase()),
        "\"{text}\" should mention \"{needle}\""
    );
}

/// The world-space polygons of a scene-wide face id (several if it was triangulated).
fn face_polygons(scene: &Scene, id: u32) -> Vec<Vec<DVec3>> {
    let (k, local) = scene.locate_face(id).expect("face id in range");
    let o = &scene.objects()[k];
    o.mesh
        .polygons_of_face(local)
        .map(|i| o.world_polygon(i))
        .collect()
}

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// Whether two polygons have the same vertices in the same cyclic order.
fn same_cycle(a: &[DVec3], b: &[DVec3]) -> bool {
    a.len() == b.len()
        && (0..a.len()).any(|s| (0..a.len()).all(|i| (a[(i + s) % a.len()] - b[i]).length() < 1e-5))
}

fn assert_bounds(b: Aabb, min: DVec3, max: DVec3) {
    assert!(
        (b.min - min).abs().max_element() < 1e-5 && (b.max - max).abs().max_element() < 1e-5,
        "bounds {:?}..{:?}, expected {min:?}..{max:?}",
        b.min,
        b.max
    );
}

/// Newell normal of a polygon (not normalised).
fn newell(p: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        n += v(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    n
}

/// The corners and outward counter-clockwise quads of the unit cube [0, 1]^3.
fn cube() -> (Vec<DVec3>, [[usize; 4]; 6]) {
    let corners = (0..8)
        .map(|i| {
            v(
                f64::from(i & 1),
                f64::from((i >> 1) & 1),
                f64::from((i >> 2) & 1),
            )
        })
        .collect();
    let quads = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    (corners, quads)
}

/// The cube's 12 triangles, each quad split (a, b, c), (a, c, d).
fn cube_triangles() -> Vec<[DVec3; 3]> {
    let (c, quads) = cube();
    quads
        .iter()
        .flat_map(|q| [[c[q[0]], c[q[1]], c[q[2]]], [c[q[0]], c[q[2]], c[q[3]]]])
        .collect()
}

// ---------------------------------------------------------------------------------
// Common errors

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let dir = TempDir::new("missing");
    for name in [
        "nope.obj",
        "nope.stl",
        "nope.ply",
        "nope.gltf",
        "nope.glb",
        "nope.toml",
    ] {
        let p = dir.0.join(name);
        match load_err(&p) {
            Error::Io { path, .. } => assert_eq!(path, p),
            e => panic!("{name}: expected an Io error, got {e:?}"),
        }
    }
}

#[test]
fn unknown_extension_is_refused() {
    let dir = TempDir::new("ext");
    for name in ["mesh.3ds", "mesh", "mesh.txt"] {
        let p = dir.write(name, "v 0 0 0\n");
        assert!(
            matches!(load_err(&p), Error::UnsupportedFormat { ref path } if *path == p),
            "{name}"
        );
    }
    // Extensions are case-insensitive.
    let p = dir.write("TRI.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_eq!(load(&p).face_count(), 1);
}

#[test]
fn empty_files_and_files_without_faces_are_empty_scenes() {
    let dir = TempDir::new("empty");
    let cases: [(&str, &[u8]); 8] = [
        ("empty.obj", b""),
        ("blank.obj", b"\n  \r\n\t\n"),
        ("comments.obj", b"# nothing\n# here\n"),
        ("points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\np 1 2 3\nl 1 2\n"),
        ("empty.stl", b""),
        ("empty.ply", b""),
        ("empty.gltf", b""),
        ("nofacets.stl", b"solid empty\nendsolid empty\n"),
    ];
    for (name, contents) in cases {
        let p = dir.write(name, contents);
        assert!(
            matches!(load_err(&p), Error::EmptyScene(ref m) if m.contains(name)),
            "{name}"
        );
    }
    // A binary STL announcing zero facets, and a PLY with vertices but no faces.
    let p = dir.write("zero.stl", binary_stl(b"", &[]));
    assert!(matches!(load_err(&p), Error::EmptyScene(_)));
    let p = dir.write(
        "novertexfaces.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
    );
    assert!(matches!(load_err(&p), Error::EmptyScene(_)));
}

// ---------------------------------------------------------------------------------
// OBJ

#[test]
fn obj_objects_groups_reference_forms_and_face_order() {
    let dir = TempDir::new("obj");
    let text = "# a comment\n\
        v 0 0 0\n\
        v 1 0 0\n\
        v 1 1 0\n\
        v 0 1 0   # a trailing comment\n\
        v 0 0 1 1.0\r\n\
        v 1 0 \\\n  1 0.5 0.5 0.5\n\
        \n\
        o first\n\
        f 1 2 3\n\
        f 1/1 2/2 3/3 4/4\n\
        vt 0 0\n\
        vn 0 0 1\n\
        g second third\n\
        f 1//1 6//1 5//1\r\n\
        f -6/1/1 -1/2/1 -5/3/1\n\
        l 1 2\n\
        p 1\n\
        s off\n\
        usemtl nowhere\n\
        curv 0 1 1 2\n";
    let p = dir.write("groups.obj", text);
    let s = load(&p);
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["first", "second"]);
    assert_eq!(s.face_count(), 4);
    assert_eq!(s.polygon_count(), 4);
    assert_eq!(
        (s.objects()[0].first_face, s.objects()[1].first_face),
        (0, 2)
    );
    // Each object holds only the vertices its faces use.
    assert_eq!(s.objects()[0].mesh.positions().len(), 4);
    assert_eq!(s.objects()[1].mesh.positions().len(), 4);
    // Face ids follow the f lines; the continued line is vertex 6 = (1, 0, 1).
    let expected: [&[DVec3]; 4] = [
        &[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.)],
        &[v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
        &[v(0., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
        &[v(0., 0., 0.), v(1., 0., 1.), v(1., 0., 0.)],
    ];
    for (id, want) in expected.iter().enumerate() {
        let polys = face_polygons(&s, id as u32);
        assert_eq!(polys.len(), 1, "face {id}");
        assert!(same_cycle(&polys[0], want), "face {id}: {:?}", polys[0]);
    }
    // `usemtl nowhere` without a library: a warning naming the line, not an error.
    assert!(
        s.report()
            .messages
            .iter()
            .any(|m| m.contains("\"nowhere\" (line 21)")),
        "{:?}",
        s.report().messages
    );
}

#[test]
fn obj_faces_before_any_group_and_empty_groups() {
    let dir = TempDir::new("obj-default");
    let p = dir.write(
        "lead.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no empty\ng\nf 3 2 1\ng a b\ng c\nf 1 2 3\n",
    );
    let s = load(&p);
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    // Leading faces take the file's name; `o empty` and `g a b` have no faces.
    assert_eq!(names, ["lead", "default", "c"]);
    assert_eq!(s.face_count(), 3);
}

#[test]
fn obj_negative_indices_match_positive_ones() {
    let dir = TempDir::new("obj-neg");
    let pos = load(&dir.write(
        "pos.obj",
        "v 0 0 0\nv 2 0 0\nv 0 2 0\nf 1 2 3\nv 0 0 3\nf 1 2 4\n",
    ));
    let neg = load(&dir.write(
        "neg.obj",
        "v 0 0 0\nv 2 0 0\nv 0 2 0\nf -3 -2 -1\nv 0 0 3\nf -4 -3 -1\n",
    ));
    for id in 0..2 {
        assert_eq!(
            face_polygons(&pos, id),
            face_polygons(&neg, id),
            "face {id}"
        );
    }
    assert_eq!(face_polygons(&neg, 1)[0][2], v(0., 0., 3.));
}

#[test]
fn obj_forward_references_are_accepted() {
    let dir = TempDir::new("obj-forward");
    let s = load(&dir.write("fwd.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
    assert_eq!(s.polygon_count(), 1);
}

#[test]
fn obj_quads_kept_and_nonplanar_quads_triangulated_with_one_id() {
    let dir = TempDir::new("obj-quad");
    let p = dir.write(
        "quads.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 1 0.5\n\
         f 1 2 3 4\n\
         f 1 2 5 4\n\
         f 3 4 1\n",
    );
    let s = load(&p);
    assert_eq!(s.face_count(), 3);
    // The planar quad stays one polygon of four vertices.
    let q = face_polygons(&s, 0);
    assert_eq!((q.len(), q[0].len()), (1, 4));
    // The non-planar one becomes two triangles that both carry id 1.
    let t = face_polygons(&s, 1);
    assert_eq!(t.len(), 2);
    assert!(t.iter().all(|p| p.len() == 3));
    assert_eq!(s.report().nonplanar_faces, 1);
    // Its triangles cover the quad's four corners and keep its orientation (+z side).
    let mut corners: Vec<DVec3> = t.iter().flatten().copied().collect();
    corners.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
    corners.dedup();
    assert_eq!(corners.len(), 4);
    assert!(t.iter().all(|p| newell(p).z > 0.0));
    // The next face id is unaffected.
    assert_eq!(face_polygons(&s, 2).len(), 1);
    assert_eq!(s.polygon_count(), 4);
}

#[test]
fn obj_coordinates_out_of_range_are_named_not_taken_for_degenerate_faces() {
    // Areas of faces at 1e200 overflow: the faces used to be dropped as degenerate and
    // the file reported empty.
    let dir = TempDir::new("obj-huge");
    let p = dir.write(
        "huge.obj",
        "v 1e200 0 0\nv 0 1e200 0\nv 0 0 1e200\nv 1e200 1e200 0\nf 1 2 3\nf 1 4 2 3\n",
    );
    let e = load_err(&p).to_string();
    assert!(e.contains("largest coordinate accepted"), "{e}");
    assert!(!e.contains("empty"), "{e}");
}

#[test]
fn obj_degenerate_faces_are_dropped_counted_and_keep_their_ids() {
    let dir = TempDir::new("obj-degenerate");
    let p = dir.write(
        "degenerate.obj",
        "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n\
         f 1 2 4\n\
         f 1 2 3\n\
         f 1 1 4\n\
         f 2 4 4 2\n\
         f 2 1 4\n",
    );
    let s = load(&p);
    assert_eq!(s.face_count(), 5);
    assert_eq!(s.polygon_count(), 2);
    assert_eq!(s.report().degenerate_faces, 3);
    assert!(
        s.report()
            .warnings()
            .iter()
            .any(|w| w.starts_with("3 degenerate"))
    );
    for id in 1..4 {
        assert!(face_polygons(&s, id).is_empty(), "face {id} dropped");
    }
    assert!(same_cycle(
        &face_polygons(&s, 4)[0],
        &[v(1., 0., 0.), v(0., 0., 0.), v(0., 1., 0.)]
    ));
}

#[test]
fn obj_materials_from_mtl_with_warnings_for_missing_ones() {
    let dir = TempDir::new("obj-mtl");
    dir.write(
        "sub/colours.mtl",
        "# colours\nnewmtl red\nKa 0 0 0\nKd 1 0 0\n\nnewmtl grey\nKd 0.5\nnewmtl bright\nKd 2 0.5 -1\nnewmtl broken\nKd 1 x 0\nnewmtl plain\n",
    );
    let p = dir.write(
        "sub/colored.obj",
        "mtllib colours.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
         f 1 2 3\n\
         usemtl red\nf 1 2 3\n\
         usemtl grey\nf 1 2 3\n\
         usemtl bright\nf 1 2 3\n\
         usemtl broken\nf 1 2 3\n\
         usemtl plain\nf 1 2 3\n\
         usemtl unknown\nf 1 2 3\n",
    );
    let s = load(&p);
    let o = &s.objects()[0];
    let c = |f: u32| o.face_color(f);
    assert_eq!(c(0), o.color, "no material: the object colour");
    assert_eq!(c(1), [1.0, 0.0, 0.0]);
    assert_eq!(c(2), [0.5, 0.5, 0.5]);
    assert_eq!(c(3), [1.0, 0.5, 0.0], "clamped to 0..=1");
    assert_eq!(c(4), [0.8, 0.8, 0.8], "malformed Kd: the MTL default");
    assert_eq!(c(5), [0.8, 0.8, 0.8], "no Kd: the MTL default");
    assert_eq!(c(6), o.color, "unknown material: the object colour");
    let messages = s.report().messages.join("\n");
    assert!(messages.contains("missing.mtl"), "{messages}");
    assert!(messages.contains("line 1:"), "{messages}");
    assert!(messages.contains("colours.mtl"), "{messages}");
    assert!(messages.contains("line 11: malformed Kd"), "{messages}");
    assert!(messages.contains("\"unknown\" (line 16)"), "{messages}");
}

#[test]
fn obj_mtllib_name_with_spaces() {
    let dir = TempDir::new("obj-mtl-space");
    dir.write("my colours.mtl", "newmtl blue\nKd 0 0 1\n");
    let p = dir.write(
        "spaced.obj",
        "mtllib my colours.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl blue\nf 1 2 3\n",
    );
    let s = load(&p);
    assert_eq!(s.objects()[0].face_color(0), [0.0, 0.0, 1.0]);
    assert!(s.report().messages.is_empty(), "{:?}", s.report().messages);
}

#[test]
fn obj_errors_name_file_and_line() {
    let dir = TempDir::new("obj-errors");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: [(&str, String, usize, &str); 14] = [
        (
            "number.obj",
            format!("{tri}v 1 2 x\n"),
            4,
            "\"x\" is not a number",
        ),
        (
            "short_v.obj",
            format!("{tri}v 1 2\n"),
            4,
            "found 2 coordinate",
        ),
        ("nan.obj", format!("{tri}v nan 0 0\n"), 4, "not finite"),
        ("inf.obj", format!("{tri}v 0 -inf 0\n"), 4, "not finite"),
        (
            "overflow.obj",
            format!("{tri}v 0 0 1e400\n"),
            4,
            "not finite",
        ),
        (
            "few.obj",
            format!("{tri}f 1 2\n"),
            4,
            "at least 3 vertices, found 2",
        ),
        ("zero.obj", format!("{tri}f 0 1 2\n"), 4, "index 0"),
        (
            "range.obj",
            format!("{tri}f 1 2 3\nf 1 2 9\n"),
            5,
            "9 is out of range: the file has 3 vertices",
        ),
        (
            "relative.obj",
            format!("{tri}f -1 -2 -4\n"),
            4,
            "-4 reaches before the first vertex (3 vertices",
        ),
        (
            "index.obj",
            format!("{tri}f 1 2 three\n"),
            4,
            "not a vertex index",
        ),
        (
            "slashes.obj",
            format!("{tri}f 1/1/1/1 2 3\n"),
            4,
            "too many '/'",
        ),
        (
            "texture.obj",
            format!("{tri}f 1/a 2 3\n"),
            4,
            "not a texture index",
        ),
        (
            "normal.obj",
            format!("{tri}f 1//0 2 3\n"),
            4,
            "not a normal index",
        ),
        // A continued line reports the line it starts on; later lines keep counting.
        (
            "continued.obj",
            "v 0 0 0\nv 1 \\\n 0 0\nv 0 1 0\nf 1 2 x\n".to_string(),
            5,
            "not a vertex index",
        ),
    ];
    for (name, text, line, needle) in cases {
        let p = dir.write(name, text);
        assert_at_line(&load_err(&p), &p, line, needle);
    }
    // CRLF files count lines the same way.
    let p = dir.write("crlf.obj", "v 0 0 0\r\nv 1 0 0\r\n\r\nv 0 1 nan\r\n");
    assert_at_line(&load_err(&p), &p, 4, "not finite");
}

#[test]
fn obj_vertex_count_per_object_survives_many_groups() {
    // 200 groups over one shared vertex pool: each object remaps only its own vertices.
    let dir = TempDir::new("obj-many");
    let mut text = String::new();
    for i in 0..=200 {
        text.push_str(&format!("v {i} 0 0\nv {i} 1 0\n"));
    }
    for i in 0..200 {
        let a = 2 * i + 1;
        text.push_str(&format!(
            "g strip{i}\nf {a} {} {} {}\n",
            a + 2,
            a + 3,
            a + 1
        ));
    }
    let s = load(&dir.write("many.obj", text));
    assert_eq!(s.objects().len(), 200);
    assert!(s.objects().iter().all(|o| o.mesh.positions().len() == 4));
    let b = s.objects()[57].bounds;
    assert_bounds(b, v(57., 0., 0.), v(58., 1., 0.));
}

#[test]
fn sponza_loads_with_every_face() {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/sponza.obj"
    ));
    if !path.exists() {
        // CI copies shared/ beside its fresh clone: there the file must be found.
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but {} is not present",
            path.display()
        );
        eprintln!(
            "SKIPPED sponza_loads_with_every_face: {} is not present (with CI set this fails)",
            path.display()
        );
        return;
    }
    let s = load(path);
    assert_eq!(s.face_count(), 262_267);
    // A triangle soup: every kept face is one triangle, every other one was degenerate.
    assert_eq!(s.polygon_count() + s.report().degenerate_faces, 262_267);
    assert_eq!(s.triangle_count(), s.polygon_count());
    let b = s.bounds();
    // The README's extent: x -11.1..11.8, y -19.2..18.0, z -1.3..14.3.
    for (got, want) in [
        (b.min.x, -11.1),
        (b.max.x, 11.8),
        (b.min.y, -19.2),
        (b.max.y, 18.0),
        (b.min.z, -1.3),
        (b.max.z, 14.3),
    ] {
        assert!((got - want).abs() < 0.1, "bounds {b:?}");
    }
}

// ---------------------------------------------------------------------------------
// STL

fn binary_stl(header: &[u8], triangles: &[[DVec3; 3]]) -> Vec<u8> {
    let mut b = vec![b' '; 80];
    b[..header.len()].copy_from_slice(header);
    b.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        b.extend([0u8; 12]); // the normal, ignored
        for p in t {
            for c in p.to_array() {
                b.extend((c as f32).to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn ascii_stl(name: &str, triangles: &[[DVec3; 3]], eol: &str) -> String {
    let mut s = format!("solid {name}{eol}");
    for t in triangles {
        s.push_str(&format!("  facet normal 0 0 0{eol}    outer loop{eol}"));
        for p in t {
            s.push_str(&format!("      vertex {} {} {}{eol}", p.x, p.y, p.z));
        }
        s.push_str(&format!("    endloop{eol}  endfacet{eol}"));
    }
    s.push_str(&format!("endsolid {name}{eol}"));
    s
}

fn assert_stl_cube(s: &Scene) {
    let tris = cube_triangles();
    assert_eq!(s.face_count(), 12);
    let o = &s.objects()[0];
    assert_eq!(o.mesh.positions().len(), 8, "corners welded");
    assert!(o.closed && o.convex, "welded cube is closed and convex");
    for (k, t) in tris.iter().enumerate() {
        assert_eq!(face_polygons(s, k as u32), vec![t.to_vec()], "facet {k}");
    }
}

#[test]
fn stl_binary_and_ascii_cubes() {
    let dir = TempDir::new("stl");
    let tris = cube_triangles();
    let s = load(&dir.write("plain.stl", binary_stl(b"binary cube", &tris)));
    assert_stl_cube(&s);
    // Binary files whose header starts with "solid " are still binary (size rule).
    let s = load(&dir.write("solid.stl", binary_stl(b"solid cube exported", &tris)));
    assert_stl_cube(&s);
    let s = load(&dir.write("ascii.stl", ascii_stl("block", &tris, "\n")));
    assert_stl_cube(&s);
    assert_eq!(s.objects()[0].name, "block");
    // "solid" without a name, CRLF, leading blank line.
    let s = load(&dir.write("crlf.stl", format!("\r\n{}", ascii_stl("", &tris, "\r\n"))));
    assert_stl_cube(&s);
    assert_eq!(s.objects()[0].name, "crlf");
}

#[test]
fn stl_degenerate_facets_keep_ids() {
    let dir = TempDir::new("stl-degenerate");
    let mut tris = cube_triangles();
    tris.insert(3, [v(0., 0., 0.), v(1., 1., 1.), v(2., 2., 2.)]);
    let s = load(&dir.write("deg.stl", binary_stl(b"", &tris)));
    assert_eq!(s.face_count(), 13);
    assert_eq!(s.polygon_count(), 12);
    assert_eq!(s.report().degenerate_faces, 1);
    assert!(face_polygons(&s, 3).is_empty());
    assert_eq!(face_polygons(&s, 4), vec![tris[4].to_vec()]);
}

#[test]
fn stl_errors_name_the_facet() {
    let dir = TempDir::new("stl-errors");
    let tris = cube_triangles();
    // Truncated in the middle of facet 5.
    let full = binary_stl(b"", &tris);
    let p = dir.write("truncated.stl", &full[..84 + 50 * 5 + 20]);
    assert_element(&load_err(&p), &p, "facet 5", "truncated");
    // Shorter than the header.
    let p = dir.write("header.stl", &binary_stl(b"cube", &tris)[..40]);
    assert_element(&load_err(&p), &p, "header", "84-byte header");
    let mut short = binary_stl(b"cube", &tris)[..40].to_vec();
    short[20] = 0;
    let p = dir.write("header0.stl", short);
    assert_element(&load_err(&p), &p, "header", "truncated");
    // A binary file starting with "solid" that is truncated is still reported as binary.
    let p = dir.write(
        "solidtrunc.stl",
        &binary_stl(b"solid x", &tris)[..84 + 50 * 2],
    );
    assert_element(&load_err(&p), &p, "facet 2", "truncated");
    // NaN and infinity in binary facets.
    let mut bad = tris.clone();
    bad[7][1].y = f64::NAN;
    let p = dir.write("nan.stl", binary_stl(b"", &bad));
    assert_element(&load_err(&p), &p, "facet 7", "vertex 1");
    let mut bad = tris.clone();
    bad[2][0].x = f64::INFINITY;
    let p = dir.write("inf.stl", binary_stl(b"", &bad));
    assert_element(&load_err(&p), &p, "facet 2", "non-finite");
    // Non-finite and overflowing values in ASCII facets.
    let text = ascii_stl("x", &tris, "\n").replacen("vertex 1 0 0", "vertex 1 0 1e39", 1);
    let first_with = tris
        .iter()
        .position(|t| t.contains(&v(1., 0., 0.)))
        .unwrap();
    let corner = tris[first_with]
        .iter()
        .position(|&p| p == v(1., 0., 0.))
        .unwrap();
    let line = text.lines().position(|l| l.contains("1e39")).unwrap() + 1;
    let p = dir.write("overflow.stl", &text);
    assert_at_line(
        &load_err(&p),
        &p,
        line,
        &format!("facet {first_with}: vertex {corner}: coordinate 1e39 is beyond"),
    );
    let p = dir.write("infinite.stl", text.replace("1e39", "1e400"));
    assert_at_line(
        &load_err(&p),
        &p,
        line,
        &format!("facet {first_with}: vertex {corner} has a non-finite coordinate"),
    );
    // A malformed ASCII facet (line 3: the first "outer loop").
    let text = ascii_stl("x", &tris, "\n").replacen("outer loop", "outer lop", 3);
    let p = dir.write("malformed.stl", text);
    assert_at_line(
        &load_err(&p),
        &p,
        3,
        "facet 0: expected \"outer loop\", found \"outer lop\"",
    );
}

#[test]
fn stl_trailing_bytes_are_a_warning() {
    let dir = TempDir::new("stl-trailing");
    let mut bytes = binary_stl(b"", &cube_triangles());
    bytes.extend([0u8; 7]);
    let s = load(&dir.write("trailing.stl", bytes));
    assert_eq!(s.face_count(), 12);
    assert!(s.report().messages.iter().any(|m| m.contains("7 bytes")));
}

// ---------------------------------------------------------------------------------
// PLY

const PLY_VERTEX_LINES: [&str; 8] = [
    "0 0 0 255 0 0",
    "1 0 0 255 0 0",
    "0 1 0 255 0 0",
    "1 1 0 255 0 0",
    "0 0 1 255 0 0",
    "1 0 1 255 0 0",
    "0 1 1 255 0 0",
    "1 1 1 255 0 0",
];

fn ascii_ply(faces: &[Vec<i64>]) -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\ncomment a cube\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n",
    );
    s.push_str(&format!(
        "element face {}\nproperty list uchar int vertex_indices\nproperty uchar flags\nelement edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        faces.len()
    ));
    for l in PLY_VERTEX_LINES {
        s.push_str(l);
        s.push('\n');
    }
    for f in faces {
        s.push_str(&f.len().to_string());
        for i in f {
            s.push_str(&format!(" {i}"));
        }
        s.push_str(" 7\n");
    }
    s.push_str("0 1\n");
    s
}

/// The header lines before the body of `ascii_ply`.
const PLY_HEADER_LINES: usize = 17;

fn cube_faces() -> Vec<Vec<i64>> {
    cube()
        .1
        .iter()
        .map(|q| q.iter().map(|&i| i as i64).collect())
        .collect()
}

/// A binary PLY of the cube: doubles and `vertex_index` as `uint` in little endian,
/// floats and `vertex_indices` as `ushort` in big endian.
fn binary_ply(little: bool, faces: &[Vec<i64>]) -> Vec<u8> {
    let (format, coord, list) = if little {
        (
            "binary_little_endian",
            "double",
            "property list uchar uint vertex_index",
        )
    } else {
        (
            "binary_big_endian",
            "float",
            "property list uchar ushort vertex_indices",
        )
    };
    let mut b = format!(
        "ply\nformat {format} 1.0\nelement vertex 8\nproperty {coord} x\nproperty {coord} y\nproperty {coord} z\nelement face {}\n{list}\nend_header\n",
        faces.len()
    )
    .into_bytes();
    let (corners, _) = cube();
    for c in corners {
        for x in c.to_array() {
            if little {
                b.extend(x.to_le_bytes());
            } else {
                b.extend((x as f32).to_be_bytes());
            }
        }
    }
    for f in faces {
        b.push(f.len() as u8);
        for &i in f {
            if little {
                b.extend((i as u32).to_le_bytes());
            } else {
                b.extend((i as u16).to_be_bytes());
            }
        }
    }
    b
}

fn assert_ply_cube(s: &Scene) {
    let (corners, quads) = cube();
    assert_eq!(s.face_count(), 6);
    assert_eq!(s.polygon_count(), 6);
    assert!(s.objects()[0].closed && s.objects()[0].convex);
    for (k, q) in quads.iter().enumerate() {
        let want: Vec<DVec3> = q.iter().map(|&i| corners[i]).collect();
        assert_eq!(face_polygons(s, k as u32), vec![want], "face {k}");
    }
}

#[test]
fn ply_ascii_and_binary_cubes() {
    let dir = TempDir::new("ply");
    let faces = cube_faces();
    assert_ply_cube(&load(&dir.write("ascii.ply", ascii_ply(&faces))));
    assert_ply_cube(&load(&dir.write("le.ply", binary_ply(true, &faces))));
    assert_ply_cube(&load(&dir.write("be.ply", binary_ply(false, &faces))));
}

#[test]
fn ply_degenerate_and_nonplanar_faces() {
    let dir = TempDir::new("ply-faces");
    let mut faces = cube_faces();
    faces.push(vec![0, 1, 1]);
    faces.push(vec![0, 1, 7, 6]); // a non-planar quad through the cube
    let s = load(&dir.write("extra.ply", ascii_ply(&faces)));
    assert_eq!(s.face_count(), 8);
    assert_eq!(s.report().degenerate_faces, 1);
    assert!(face_polygons(&s, 6).is_empty());
    let quad = face_polygons(&s, 7);
    assert!(quad.len() == 2 || (quad.len() == 1 && quad[0].len() == 4));
}

#[test]
fn ply_errors_name_element_and_line() {
    let dir = TempDir::new("ply-errors");
    let body = PLY_HEADER_LINES + 1;
    // Out-of-range and negative indices: ASCII names the line, binary the element.
    let mut faces = cube_faces();
    faces[2][1] = 8;
    let p = dir.write("range.ply", ascii_ply(&faces));
    assert_at_line(
        &load_err(&p),
        &p,
        body + 8 + 2,
        "face 2: vertex index 8 is out of range",
    );
    let p = dir.write("range_le.ply", binary_ply(true, &faces));
    assert_element(&load_err(&p), &p, "face 2", "index 8 is out of range");
    let mut faces = cube_faces();
    faces[4][0] = -1;
    let p = dir.write("negative.ply", ascii_ply(&faces));
    assert_at_line(&load_err(&p), &p, body + 8 + 4, "-1 is out of range");
    // Too few corners.
    let mut faces = cube_faces();
    faces[1] = vec![0, 1];
    let p = dir.write("few.ply", ascii_ply(&faces));
    assert_at_line(&load_err(&p), &p, body + 8 + 1, "at least 3 vertices");
    // Non-finite coordinates.
    // (ply-rs refuses a literal `nan` in ASCII bodies; a float overflowing is infinite.)
    let text = ascii_ply(&cube_faces()).replacen("1 1 0 255", "1 1e39 0 255", 1);
    let p = dir.write("overflow.ply", text);
    assert_at_line(&load_err(&p), &p, body + 3, "vertex 3: non-finite");
    let text = ascii_ply(&cube_faces()).replacen("1 1 0 255", "1 nan 0 255", 1);
    let p = dir.write("nan.ply", text);
    assert_at_line(&load_err(&p), &p, body + 3, "vertex 3");
    let mut bytes = binary_ply(false, &cube_faces());
    let header_len_be = bytes.len() - 8 * 12 - 6 * 9;
    bytes[header_len_be + 2 * 12..header_len_be + 2 * 12 + 4]
        .copy_from_slice(&f32::NAN.to_be_bytes());
    let p = dir.write("nan_be.ply", bytes);
    assert_element(&load_err(&p), &p, "vertex 2", "non-finite");
    let mut bytes = binary_ply(true, &cube_faces());
    let header_len = bytes.len() - 8 * 24 - 6 * 17;
    bytes[header_len + 5 * 24 + 8..header_len + 5 * 24 + 16]
        .copy_from_slice(&f64::INFINITY.to_le_bytes());
    let p = dir.write("inf.ply", bytes);
    assert_element(&load_err(&p), &p, "vertex 5", "non-finite");
    // A malformed number.
    let text = ascii_ply(&cube_faces()).replacen("0 1 1 255", "0 one 1 255", 1);
    let p = dir.write("number.ply", text);
    assert_at_line(&load_err(&p), &p, body + 6, "vertex 6");
    // Truncated binary and ASCII bodies.
    let bytes = binary_ply(false, &cube_faces());
    let p = dir.write("truncated.ply", &bytes[..bytes.len() - 5]);
    assert_element(&load_err(&p), &p, "face 5", "truncated");
    let bytes = binary_ply(true, &cube_faces());
    let p = dir.write("truncated_vertices.ply", &bytes[..header_len + 3 * 24 + 4]);
    assert_element(&load_err(&p), &p, "vertex 3", "truncated");
    let text = ascii_ply(&cube_faces());
    let cut = text.lines().take(body + 3).collect::<Vec<_>>().join("\n") + "\n";
    let p = dir.write("truncated_ascii.ply", cut);
    assert_at_line(&load_err(&p), &p, body + 4, "truncated");
    // An element without properties and an absurd count costs nothing to skip.
    let mut bytes = binary_ply(true, &cube_faces());
    let at = bytes.windows(10).position(|w| w == b"end_header").unwrap();
    bytes.splice(at..at, b"element marker 4000000000\n".iter().copied());
    assert_ply_cube(&load(&dir.write("marker.ply", bytes)));
    // A broken header.
    let p = dir.write(
        "header.ply",
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty flot x\nend_header\n",
    );
    assert_at_line(&load_err(&p), &p, 4, "header");
    let p = dir.write("magic.ply", "plx\nformat ascii 1.0\nend_header\n");
    assert_at_line(&load_err(&p), &p, 1, "header");
    // Missing properties.
    let p = dir.write(
        "noz.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
    );
    assert_at_line(&load_err(&p), &p, 3, "vertex element has no property z");
    let p = dir.write(
        "nolist.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int corners\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    assert_at_line(&load_err(&p), &p, 7, "face element has no vertex_indices");
    let p = dir.write(
        "floatlist.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    assert_at_line(&load_err(&p), &p, 8, "floating-point");
}

// ---------------------------------------------------------------------------------
// glTF

/// Standard base64 with padding (enough for data URIs in tests).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Builds the binary buffer and the `bufferViews`/`accessors` JSON of a glTF file.
#[derive(Default)]
struct GltfBuffer {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl GltfBuffer {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}}}"#,
            self.bin.len(),
            bytes.len()
        ));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A VEC3 float accessor; returns its index.
    fn positions(&mut self, points: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = points
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        let view = self.view(&bytes);
        let fin = |k: usize, f: fn(f32, f32) -> f32, init: f32| {
            points
                .iter()
                .map(|p| p[k])
                .filter(|x| x.is_finite())
                .fold(init, f)
        };
        let min = [0, 1, 2].map(|k| fin(k, f32::min, f32::MAX));
        let max = [0, 1, 2].map(|k| fin(k, f32::max, f32::MIN));
        self.accessors.push(format!(
            r#"{{"bufferView": {view}, "componentType": 5126, "count": {}, "type": "VEC3", "min": {min:?}, "max": {max:?}}}"#,
            points.len()
        ));
        self.accessors.len() - 1
    }

    /// An unsigned short SCALAR accessor; returns its index.
    fn indices(&mut self, indices: &[u16]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors.push(format!(
            r#"{{"bufferView": {view}, "componentType": 5123, "count": {}, "type": "SCALAR"}}"#,
            indices.len()
        ));
        self.accessors.len() - 1
    }

    /// The document with the buffer given by `buffer_json` (uri or none for GLB).
    fn json(&self, rest: &str, buffer_json: &str) -> String {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{buffer_json}], "bufferViews": [{}], "accessors": [{}], {rest}}}"#,
            self.views.join(", "),
            self.accessors.join(", ")
        )
    }

    fn gltf_embedded(&self, rest: &str) -> String {
        self.json(
            rest,
            &format!(
                r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
                self.bin.len(),
                base64(&self.bin)
            ),
        )
    }

    fn glb(&self, rest: &str) -> Vec<u8> {
        let mut json = self
            .json(rest, &format!(r#"{{"byteLength": {}}}"#, self.bin.len()))
            .into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }
}

const SQUARE: [[f32; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];

/// A unit square mesh used by a parent node and its child (default scene), and by a
/// node of another scene.
fn hierarchy() -> (GltfBuffer, String) {
    hierarchy_with(true)
}

fn hierarchy_with(default_scene: bool) -> (GltfBuffer, String) {
    let mut g = GltfBuffer::default();
    let pos = g.positions(&SQUARE);
    let idx = g.indices(&[0, 1, 2, 0, 2, 3]);
    let half = std::f32::consts::FRAC_1_SQRT_2;
    let rest = format!(
        r#""materials": [{{"name": "paint", "pbrMetallicRoughness": {{"baseColorFactor": [0.2, 0.4, 0.6, 1.0]}}}}],
           "meshes": [{{"name": "square", "primitives": [{{"attributes": {{"POSITION": {pos}}}, "indices": {idx}, "material": 0}}]}}],
           "nodes": [
             {{"name": "parent", "translation": [10, 0, 0], "scale": [2, 2, 2], "children": [1], "mesh": 0}},
             {{"name": "child", "rotation": [0, 0, {half}, {half}], "translation": [0, 0, 5], "mesh": 0}},
             {{"name": "elsewhere", "mesh": 0}}
           ],
           "scenes": [{{"nodes": [2]}}, {{"nodes": [0]}}]"#
    );
    let rest = if default_scene {
        rest + r#", "scene": 1"#
    } else {
        rest
    };
    (g, rest)
}

fn assert_hierarchy(s: &Scene) {
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["parent", "child"], "the default scene only");
    assert_eq!(s.up(), DVec3::Y);
    assert_eq!(s.face_count(), 4);
    // parent: T(10, 0, 0) S(2): the square spans x 10..12, y 0..2.
    assert_bounds(s.objects()[0].bounds, v(10., 0., 0.), v(12., 2., 0.));
    // child: parent * T(0, 0, 5) Rz(90°): (x, y) -> (-y, x), lifted to z 5, then
    // scaled by 2 and moved by 10 along x.
    assert_bounds(s.objects()[1].bounds, v(8., 0., 10.), v(10., 2., 10.));
    assert!(Arc::ptr_eq(&s.objects()[0].mesh, &s.objects()[1].mesh));
    let c = s.objects()[1].face_color(0);
    assert!((c[0] - 0.2).abs() < 1e-6 && (c[1] - 0.4).abs() < 1e-6 && (c[2] - 0.6).abs() < 1e-6);
    // Face ids: triangles in index order, node by node.
    assert!(same_cycle(
        &face_polygons(s, 1)[0],
        &[v(10., 0., 0.), v(12., 2., 0.), v(10., 2., 0.)]
    ));
    assert!(same_cycle(
        &face_polygons(s, 2)[0],
        &[v(10., 0., 10.), v(10., 2., 10.), v(8., 2., 10.)]
    ));
}

#[test]
fn gltf_embedded_and_glb_node_hierarchy() {
    let dir = TempDir::new("gltf");
    let (g, rest) = hierarchy();
    assert_hierarchy(&load(&dir.write("tree.gltf", g.gltf_embedded(&rest))));
    assert_hierarchy(&load(&dir.write("tree.glb", g.glb(&rest))));
    // Without a default scene, scene 0 is placed (the scenes are alternatives, not
    // parts: drawing them all would overlap them), and a warning says so.
    let (g, rest) = hierarchy_with(false);
    let s = load(&dir.write("all.gltf", g.gltf_embedded(&rest)));
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["elsewhere"]);
    let messages = s.report().messages.join("\n");
    assert!(
        messages.contains("2 scenes") && messages.contains("scene 0"),
        "{messages}"
    );
}

#[test]
fn gltf_external_buffer() {
    let dir = TempDir::new("gltf-external");
    let (g, rest) = hierarchy();
    let json = g.json(
        &rest,
        &format!(
            r#"{{"byteLength": {}, "uri": "data/square.bin"}}"#,
            g.bin.len()
        ),
    );
    let p = dir.write("external.gltf", &json);
    // The error names the glTF, the buffer and its URI, then the missing file.
    let e = load_err(&p);
    assert_element(&e, &p, "buffer 0 (uri \"data/square.bin\")", "no such file");
    assert!(
        e.to_string()
            .contains(&format!("{}", dir.0.join("data/square.bin").display())),
        "{e}"
    );
    dir.write("data/square.bin", &g.bin);
    assert_hierarchy(&load(&p));
    // A buffer shorter than it says.
    dir.write("data/square.bin", &g.bin[..20]);
    assert_element(&load_err(&p), &p, "buffer 0", "truncated");
}

#[test]
fn gltf_strips_fans_and_skipped_points() {
    let dir = TempDir::new("gltf-modes");
    let mut g = GltfBuffer::default();
    let strip = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [1., 1., 0.]]);
    let fan = g.positions(&[
        [0., 0., 0.],
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [-1., 1., 0.],
    ]);
    let rest = format!(
        r#""meshes": [{{"primitives": [
             {{"attributes": {{"POSITION": {strip}}}, "mode": 5}},
             {{"attributes": {{"POSITION": {fan}}}, "mode": 0}},
             {{"attributes": {{"POSITION": {fan}}}, "mode": 6}}]}}],
           "nodes": [{{"mesh": 0}}]"#
    );
    let s = load(&dir.write("modes.gltf", g.gltf_embedded(&rest)));
    // A 4-vertex strip makes 2 triangles, a 5-vertex fan 3; every one faces +z.
    assert_eq!(s.face_count(), 5);
    for id in 0..5 {
        let p = &face_polygons(&s, id)[0];
        assert!(newell(p).z > 0.0, "face {id} is clockwise: {p:?}");
    }
    assert!(same_cycle(
        &face_polygons(&s, 2)[0],
        &[v(1., 0., 0.), v(1., 1., 0.), v(0., 0., 0.)]
    ));
    assert!(
        s.report()
            .messages
            .iter()
            .any(|m| m.contains("primitive 1") && m.contains("Points")),
        "{:?}",
        s.report().messages
    );
}

#[test]
fn gltf_errors_name_mesh_primitive_and_accessor() {
    let dir = TempDir::new("gltf-errors");
    let scene = r#""nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0"#;
    let mesh = |pos: usize, idx: usize| {
        format!(
            r#""meshes": [{{"name": "m", "primitives": [{{"attributes": {{"POSITION": {pos}}}, "indices": {idx}}}]}}], {scene}"#
        )
    };
    // An index beyond the vertices.
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 7]));
    let p = dir.write("range.gltf", g.gltf_embedded(&mesh(p0, i0)));
    // The message names the element, not the value the buffer holds there.
    let e = load_err(&p);
    assert_element(
        &e,
        &p,
        "mesh 0 \"m\" primitive 0 accessor 1 (indices)",
        "element 2 is not a vertex of the primitive (it has 4 vertices)",
    );
    let message = e.to_string().replace(&p.display().to_string(), "");
    assert!(!message.contains('7'), "{e}");
    // NaN and infinite positions.
    for (name, bad) in [("nan.gltf", f32::NAN), ("inf.gltf", f32::NEG_INFINITY)] {
        let mut g = GltfBuffer::default();
        let mut pts = SQUARE;
        pts[2][1] = bad;
        let (p0, i0) = (g.positions(&pts), g.indices(&[0, 1, 2]));
        let p = dir.write(name, g.gltf_embedded(&mesh(p0, i0)));
        assert_element(
            &load_err(&p),
            &p,
            "accessor 0 (POSITION)",
            "element 2 is not finite",
        );
    }
    // An accessor reaching past its buffer view.
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2]));
    let text = g
        .gltf_embedded(&mesh(p0, i0))
        .replacen(r#""count": 4"#, r#""count": 40"#, 1);
    let p = dir.write("overrun.gltf", text);
    assert_element(&load_err(&p), &p, "accessor 0 (POSITION)", "overrun");
    // Triangles that do not add up.
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2, 3]));
    let p = dir.write("partial.gltf", g.gltf_embedded(&mesh(p0, i0)));
    assert_element(&load_err(&p), &p, "accessor 1 (indices)", "whole triangles");
    // Malformed JSON, and a document the crate's validation refuses.
    let p = dir.write("syntax.gltf", "{\"asset\": {\"version\": \"2.0\"},");
    assert_element(&load_err(&p), &p, "document", "");
    let p = dir.write(
        "invalid.gltf",
        r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": 3}]}"#,
    );
    assert_element(&load_err(&p), &p, "document", "");
    // Truncated GLB files.
    let (g, rest) = hierarchy();
    let glb = g.glb(&rest);
    for cut in [8, 30, glb.len() - 10] {
        let p = dir.write("truncated.glb", &glb[..cut]);
        let e = load_err(&p);
        assert!(
            matches!(e, Error::Format { .. }) && e.to_string().contains("truncated.glb"),
            "cut at {cut}: {e}"
        );
    }
    // A node that is its own child (a cycle).
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2]));
    let text = g.gltf_embedded(&format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {p0}}}, "indices": {i0}}}]}}], "nodes": [{{"mesh": 0, "children": [0]}}], "scenes": [{{"nodes": [0]}}]"#
    ));
    let p = dir.write("cycle.gltf", text);
    assert_element(&load_err(&p), &p, "node 0", "child");
}

#[test]
fn gltf_interleaved_strides_and_sparse_accessors() {
    let dir = TempDir::new("gltf-sparse");
    let mut g = GltfBuffer::default();
    // Positions interleaved with a 4-byte pad: stride 16.
    let mut interleaved = Vec::new();
    for p in SQUARE {
        interleaved.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        interleaved.extend([0xAB; 4]);
    }
    let view = g.view(&interleaved);
    g.views[view] = g.views[view].replace('}', r#", "byteStride": 16}"#);
    // Sparse: vertex 2 moves to (3, 3, 0); indices u8, values f32.
    let sparse_indices = g.view(&[2u8]);
    let sparse_values = g.view(
        &[3f32, 3., 0.]
            .iter()
            .flat_map(|c| c.to_le_bytes())
            .collect::<Vec<u8>>(),
    );
    g.accessors.push(format!(
        r#"{{"bufferView": {view}, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [3, 3, 0],
            "sparse": {{"count": 1, "indices": {{"bufferView": {sparse_indices}, "componentType": 5121}}, "values": {{"bufferView": {sparse_values}}}}}}}"#
    ));
    let pos = g.accessors.len() - 1;
    let idx = g.indices(&[0, 1, 2, 0, 2, 3]);
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}, "indices": {idx}}}]}}], "nodes": [{{"mesh": 0}}]"#
    );
    let s = load(&dir.write("sparse.gltf", g.gltf_embedded(&rest)));
    assert_bounds(s.objects()[0].bounds, v(0., 0., 0.), v(3., 3., 0.));
    assert!(same_cycle(
        &face_polygons(&s, 0)[0],
        &[v(0., 0., 0.), v(1., 0., 0.), v(3., 3., 0.)]
    ));
    // A sparse index beyond the accessor's count.
    let mut bad = GltfBuffer {
        bin: g.bin.clone(),
        views: g.views.clone(),
        accessors: g.accessors.clone(),
    };
    let at = bad.bin.len();
    bad.bin.push(9);
    bad.views.push(format!(
        r#"{{"buffer": 0, "byteOffset": {at}, "byteLength": 1}}"#
    ));
    bad.accessors[pos] = bad.accessors[pos].replace(
        &format!(r#""indices": {{"bufferView": {sparse_indices}"#),
        &format!(r#""indices": {{"bufferView": {}"#, bad.views.len() - 1),
    );
    let p = dir.write("sparse_bad.gltf", bad.gltf_embedded(&rest));
    let e = load_err(&p);
    assert_element(
        &e,
        &p,
        "accessor 0 (POSITION)",
        "sparse substitution 0 targets an element beyond the accessor's count",
    );
    let message = e.to_string().replace(&p.display().to_string(), "");
    assert!(!message.contains('9'), "{e}");
    // A sparse accessor without a buffer view declaring billions of zeros.
    let mut huge = GltfBuffer {
        bin: g.bin.clone(),
        views: g.views.clone(),
        accessors: g.accessors.clone(),
    };
    huge.accessors[pos] = format!(
        r#"{{"componentType": 5126, "count": 300000000, "type": "VEC3", "min": [0, 0, 0], "max": [3, 3, 0],
            "sparse": {{"count": 1, "indices": {{"bufferView": {sparse_indices}, "componentType": 5121}}, "values": {{"bufferView": {sparse_values}}}}}}}"#
    );
    let p = dir.write("viewless.gltf", huge.gltf_embedded(&rest));
    assert_element(
        &load_err(&p),
        &p,
        "accessor 0 (POSITION)",
        "without a buffer view",
    );
    // A stride smaller than the element.
    let mut small = GltfBuffer {
        bin: g.bin.clone(),
        views: g.views.clone(),
        accessors: g.accessors.clone(),
    };
    small.views[view] = small.views[view].replace(r#""byteStride": 16"#, r#""byteStride": 8"#);
    let p = dir.write("stride.gltf", small.gltf_embedded(&rest));
    assert_element(&load_err(&p), &p, "accessor 0 (POSITION)", "stride 8");
}

#[test]
fn gltf_zero_scale_nodes_are_skipped_with_a_warning() {
    let dir = TempDir::new("gltf-hidden");
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2]));
    let text = g.gltf_embedded(&format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {p0}}}, "indices": {i0}}}]}}],
           "nodes": [{{"name": "hidden", "mesh": 0, "scale": [0, 0, 0]}}, {{"name": "shown", "mesh": 0}}],
           "scenes": [{{"nodes": [0, 1]}}]"#
    ));
    let s = load(&dir.write("hidden.gltf", text));
    assert_eq!(s.objects().len(), 1);
    assert_eq!(s.objects()[0].name, "shown");
    assert!(s.report().messages.iter().any(|m| m.contains("hidden")));
}

// ---------------------------------------------------------------------------------
// Scene TOML

const COLUMN_OBJ: &str = "o shaft\nv -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n\
    v -0.5 -0.5 4\nv 0.5 -0.5 4\nv 0.5 0.5 4\nv -0.5 0.5 4\n\
    f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

/// The complete example of docs/scene-files.md, with the mesh files it references.
#[test]
fn the_documented_example_loads() {
    let doc = include_str!("../../../docs/scene-files.md");
    let start = doc.find("```toml\n").expect("a toml block") + "```toml\n".len();
    let example = &doc[start..start + doc[start..].find("```").unwrap()];
    let dir = TempDir::new("doc");
    dir.write("meshes/column.obj", COLUMN_OBJ);
    let (g, rest) = hierarchy();
    dir.write("meshes/teapot.gltf", g.gltf_embedded(&rest));
    let p = dir.write("atrium.toml", example);
    let s = load(&p);
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "floor",
            "column west",
            "column east",
            "teapot/parent",
            "teapot/child",
            "sphere 4",
            "box 5",
            "torus 6",
            "cone 7"
        ]
    );
    assert_eq!(s.up(), DVec3::Z);
    let cam = s.camera().expect("a camera");
    assert_eq!(
        (cam.eye, cam.target, cam.up),
        (v(0., -10., 2.), v(0., 10., 4.), DVec3::Z)
    );
    assert_eq!(
        cam.projection,
        Projection::Perspective {
            fov_y_degrees: 60.0
        }
    );
    assert_eq!((cam.near, cam.far), (0.1, 100.0));
    // The column file is read once and shared; `closed` overrides detection.
    let o = s.objects();
    assert!(Arc::ptr_eq(&o[1].mesh, &o[2].mesh));
    assert!(o[1].closed);
    assert_bounds(o[1].bounds, v(-3.5, -0.5, 0.), v(-2.5, 0.5, 4.));
    assert_bounds(o[2].bounds, v(2.5, -0.5, 0.), v(3.5, 0.5, 6.));
    // The floor grid, turned from facing +y to facing +z.
    assert_bounds(o[0].bounds, v(-10., -15., 0.), v(10., 15., 0.));
    let up_face = face_polygons(&s, 0);
    assert!(newell(&up_face[0]).z > 0.0);
    // The box placed by a row-major matrix: translation (5, 5, 0.25).
    assert_bounds(o[6].bounds, v(4.5, 4., 0.), v(5.5, 6., 0.5));
    // The glTF nodes keep their own transforms, composed after the table's.
    // parent: square x 10..12, y 0..2 (z 0); table: scale 0.5, rotate x 90°
    // ((x, y, z) -> (x, -z, y)), translate (0, 4, 0).
    assert_bounds(o[3].bounds, v(5., 4., 0.), v(6., 4., 1.));
    // File colours win over the table's, which colours faces without one.
    assert_eq!(o[3].color, [0.9, 0.5, 0.2]);
    let c = o[3].face_color(0);
    assert!((c[0] - 0.2).abs() < 1e-6 && (c[1] - 0.4).abs() < 1e-6 && (c[2] - 0.6).abs() < 1e-6);
    assert!(o[5].convex && o[8].convex);
    // Face ids follow the tables.
    assert_eq!(o[1].first_face, 24);
    assert_eq!(o[2].first_face, 30);
}

#[test]
fn toml_rotation_order_and_uniform_scale() {
    let dir = TempDir::new("toml-rotate");
    let p = dir.write(
        "r.toml",
        "[[object]]\nprimitive = \"box\"\nsize = [2, 4, 6]\nrotate = [90, 90, 0]\nscale = 0.5\ntranslate = [1, 2, 3]\n",
    );
    let s = load(&p);
    // S: half extents (0.5, 1, 1.5); Rx(90): (x, y, z) -> (x, -z, y) gives (0.5, 1.5, 1);
    // then Ry(90): (x, y, z) -> (z, y, -x) gives (1, 1.5, 0.5).
    assert_bounds(s.objects()[0].bounds, v(0., 0.5, 2.5), v(2., 3.5, 3.5));
}

#[test]
fn toml_primitives_match_their_generators() {
    let dir = TempDir::new("toml-prims");
    let p = dir.write(
        "p.toml",
        "[[object]]\nprimitive = \"sphere\"\nsegments = 8\nrings = 4\n\
         [[object]]\nprimitive = \"torus\"\nsegments = 6\nsides = 5\n\
         [[object]]\nprimitive = \"cone\"\nsegments = 7\n\
         [[object]]\nprimitive = \"grid\"\nnx = 3\nnz = 2\n\
         [[object]]\nprimitive = \"box\"\n",
    );
    let s = load(&p);
    let faces: Vec<u32> = s.objects().iter().map(|o| o.mesh.face_count()).collect();
    assert_eq!(faces, [2 * 8 * 3, 6 * 5, 7 + 1, 3 * 2, 6]);
    let closed: Vec<bool> = s.objects().iter().map(|o| o.closed).collect();
    assert_eq!(closed, [true, true, true, false, true]);
    assert_eq!(s.camera(), None);
}

/// A primitive's closed and convex flags are set by construction (no edge adjacency is
/// built for them: a grid of 20 million quads spent 43 % of its loading there), so
/// they must be what the adjacency finds, for every shape and small tessellations.
#[test]
fn toml_primitive_flags_are_what_the_adjacency_finds() {
    use obscura::scene::{EdgeAdjacency, is_convex_closed};
    let dir = TempDir::new("toml-prim-flags");
    let tables = [
        "primitive = \"box\"",
        "primitive = \"box\"\nsize = [3, 0.5, 2]",
        "primitive = \"sphere\"\nsegments = 3\nrings = 2",
        "primitive = \"sphere\"\nsegments = 8\nrings = 4",
        "primitive = \"sphere\"\nsegments = 31\nrings = 17",
        "primitive = \"torus\"\nsegments = 3\nsides = 3",
        "primitive = \"torus\"\nsegments = 12\nsides = 7",
        "primitive = \"cone\"\nsegments = 3",
        "primitive = \"cone\"\nsegments = 40\nheight = 0.1",
        "primitive = \"grid\"",
        "primitive = \"grid\"\nnx = 3\nnz = 2",
    ];
    let text: String = tables
        .iter()
        .map(|t| format!("[[object]]\n{t}\n"))
        .collect();
    let s = load(&dir.write("p.toml", &text));
    assert_eq!(s.objects().len(), tables.len());
    for (o, t) in s.objects().iter().zip(tables) {
        let adj = EdgeAdjacency::new(&o.mesh);
        let closed = adj.is_closed();
        let convex = closed && is_convex_closed(&o.mesh, &adj, 1e-9);
        assert_eq!((o.closed, o.convex), (closed, convex), "{t}");
    }
    // Given flags still win.
    let s = load(&dir.write(
        "q.toml",
        "[[object]]\nprimitive = \"sphere\"\nclosed = false\n",
    ));
    assert_eq!(
        (s.objects()[0].closed, s.objects()[0].convex),
        (false, false)
    );
}

#[test]
fn toml_orthographic_camera_with_fitted_range() {
    let dir = TempDir::new("toml-ortho");
    let p = dir.write(
        "o.toml",
        "[camera]\neye = [0, 0, 10]\ntarget = [0, 0, 0]\northo_height = 3\n\n[[object]]\nprimitive = \"box\"\n",
    );
    let s = load(&p);
    let c = s.camera().unwrap();
    assert_eq!(c.projection, Projection::Orthographic { height: 3.0 });
    assert_eq!(c.up, DVec3::Y, "default up");
    // The unit box spans depths 9.5..10.5 from the eye.
    assert!(c.near <= 9.5 && c.far >= 10.5 && c.far < 11.0, "{c:?}");
}

#[test]
fn toml_camera_with_a_lens() {
    let dir = TempDir::new("toml-lens");
    let p = dir.write(
        "lens.toml",
        "[camera]\neye = [0, 0, 10]\ntarget = [0, 0, 0]\nshift = [0.125, -0.25]\n\
         pixel_aspect = 1.5\n\n[[object]]\nprimitive = \"box\"\n",
    );
    let c = *load(&p).camera().unwrap();
    assert_eq!(c.lens.shift, glam::DVec2::new(0.125, -0.25));
    assert_eq!(c.lens.pixel_aspect, 1.5);
    // Without the keys, the centred lens.
    let p = dir.write(
        "centred.toml",
        "[camera]\neye = [0, 0, 10]\ntarget = [0, 0, 0]\n\n[[object]]\nprimitive = \"box\"\n",
    );
    assert_eq!(load(&p).camera().unwrap().lens, obscura::Lens::CENTRED);
    // A bad lens is refused at the camera's line.
    let p = dir.write(
        "bad.toml",
        "[[object]]\nprimitive = \"box\"\n\n[camera]\neye = [0, 0, 10]\ntarget = [0, 0, 0]\n\
         pixel_aspect = -1\n",
    );
    assert_at_line(&load_err(&p), &p, 4, "pixel aspect -1e0 positive");
}

#[test]
fn toml_errors_name_the_line() {
    let dir = TempDir::new("toml-errors");
    let obj = "[[object]]\nprimitive = \"box\"\n";
    let cases: [(&str, String, usize, &str); 17] = [
        ("syntax.toml", format!("{obj}size == 2\n"), 3, ""),
        (
            "unknown.toml",
            format!("{obj}\ncolour = [1, 0, 0]\n"),
            4,
            "unknown field `colour`",
        ),
        (
            "unknown_top.toml",
            format!("camara = 1\n{obj}"),
            1,
            "unknown field `camara`",
        ),
        (
            "camera_key.toml",
            format!("{obj}[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfocal = 3\n"),
            6,
            "unknown field `focal`",
        ),
        (
            "type.toml",
            format!("{obj}size = \"big\"\n"),
            3,
            "invalid type",
        ),
        (
            "scale_type.toml",
            format!("{obj}scale = \"x\"\n"),
            3,
            "a number or an array",
        ),
        (
            "primitive.toml",
            "[[object]]\nprimitive = \"teapot\"\n".into(),
            2,
            "unknown primitive \"teapot\"",
        ),
        (
            "param.toml",
            format!("{obj}radius = 2\n"),
            3,
            "`radius` does not apply to a box",
        ),
        (
            "negative.toml",
            "[[object]]\nprimitive = \"sphere\"\n\nradius = -1\n".into(),
            4,
            "positive",
        ),
        (
            "segments.toml",
            "[[object]]\nprimitive = \"cone\"\nsegments = 2\n".into(),
            3,
            "at least 3",
        ),
        (
            "huge.toml",
            "[[object]]\nprimitive = \"grid\"\nnx = 100000\nnz = 100000\n".into(),
            2,
            "at most",
        ),
        (
            "both.toml",
            "[[object]]\nmesh = \"a.obj\"\nprimitive = \"box\"\n".into(),
            3,
            "not both",
        ),
        (
            "neither.toml",
            "[[object]]\nname = \"x\"\n".into(),
            1,
            "neither",
        ),
        (
            "zero_scale.toml",
            format!("{obj}scale = [1, 0, 1]\n"),
            3,
            "non-zero",
        ),
        (
            "affine.toml",
            format!("{obj}matrix = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]\n"),
            3,
            "affine",
        ),
        (
            "color.toml",
            format!("{obj}color = [1.5, 0, 0]\n"),
            3,
            "0..=1",
        ),
        (
            "camera.toml",
            format!("{obj}\n[camera]\neye = [1, 2, 3]\ntarget = [1, 2, 3]\n"),
            4,
            "eye is on the target",
        ),
    ];
    for (name, text, line, needle) in cases {
        let p = dir.write(name, text);
        assert_at_line(&load_err(&p), &p, line, needle);
    }
    let p = dir.write("nan.toml", format!("{obj}translate = [0, nan, 0]\n"));
    assert_at_line(&load_err(&p), &p, 3, "finite");
    let p = dir.write(
        "matrix_mix.toml",
        format!("{obj}scale = 2\nmatrix = [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n"),
    );
    assert_at_line(&load_err(&p), &p, 4, "not both");
    let p = dir.write("matrix_len.toml", format!("{obj}matrix = [1, 0, 0]\n"));
    assert_at_line(&load_err(&p), &p, 3, "16 finite numbers");
    let p = dir.write("include.toml", "[[object]]\nmesh = \"other.toml\"\n");
    assert_at_line(&load_err(&p), &p, 2, "cannot include");
    let p = dir.write("ext.toml", "[[object]]\nmesh = \"model.3ds\"\n");
    assert_at_line(&load_err(&p), &p, 2, "unsupported");
    let p = dir.write(
        "mesh_param.toml",
        "[[object]]\nmesh = \"a.obj\"\nsegments = 3\n",
    );
    assert_at_line(&load_err(&p), &p, 3, "does not apply to a mesh file");
    // No object at all.
    let p = dir.write("nothing.toml", "up = [0, 0, 1]\n");
    assert!(matches!(load_err(&p), Error::EmptyScene(_)));
}

#[test]
fn toml_errors_in_referenced_files_name_both_files() {
    let dir = TempDir::new("toml-ref");
    let p = dir.write(
        "s.toml",
        "[[object]]\nprimitive = \"box\"\n\n[[object]]\nmesh = \"parts/missing.obj\"\n",
    );
    match load_err(&p) {
        Error::Io { path, source } => {
            assert!(path.ends_with("parts/missing.obj"));
            assert!(
                source.to_string().contains(&format!("{}:5", p.display())),
                "{source}"
            );
        }
        e => panic!("expected an Io error, got {e:?}"),
    }
    let bad = dir.write("parts/bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 5\n");
    let p = dir.write("t.toml", "[[object]]\nmesh = \"parts/bad.obj\"\n");
    let e = load_err(&p);
    assert_at_line(&e, &bad, 4, "out of range");
    assert!(e.to_string().contains(&format!("{}:2", p.display())), "{e}");
    let stl = dir.write("parts/bad.stl", &binary_stl(b"", &cube_triangles())[..100]);
    let p = dir.write("u.toml", "[[object]]\nmesh = \"parts/bad.stl\"\n");
    assert_element(&load_err(&p), &stl, "facet 0", "u.toml:2");
}

#[test]
fn toml_mesh_files_with_several_objects_and_all_formats() {
    let dir = TempDir::new("toml-multi");
    dir.write(
        "two.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\no a\nf 1 2 3\no b\nf 1 3 2\nf 2 3 1\n",
    );
    dir.write("cube.stl", binary_stl(b"", &cube_triangles()));
    dir.write("cube.ply", ascii_ply(&cube_faces()));
    let (g, rest) = hierarchy();
    dir.write("tree.glb", g.glb(&rest));
    let p = dir.write(
        "all.toml",
        "[[object]]\nname = \"pair\"\nmesh = \"two.obj\"\ntranslate = [0, 0, 7]\ncolor = [0, 1, 0]\nclosed = false\n\
         [[object]]\nmesh = \"cube.stl\"\n\
         [[object]]\nmesh = \"./cube.ply\"\ntranslate = [5, 0, 0]\n\
         [[object]]\nmesh = \"cube.ply\"\n\
         [[object]]\nmesh = \"tree.glb\"\nscale = 2\n",
    );
    let s = load(&p);
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "pair/a",
            "pair/b",
            "cube",
            "cube",
            "cube",
            "tree/parent",
            "tree/child"
        ]
    );
    let o = s.objects();
    assert_eq!(o[0].color, [0.0, 1.0, 0.0]);
    assert_bounds(o[1].bounds, v(0., 0., 7.), v(1., 1., 7.));
    assert!(o[2].closed && o[3].closed);
    // "./cube.ply" and "cube.ply" are one file: read once.
    assert!(Arc::ptr_eq(&o[3].mesh, &o[4].mesh));
    assert_bounds(o[3].bounds, v(5., 0., 0.), v(6., 1., 1.));
    // glTF node transforms composed with the table's scale.
    assert_bounds(o[6].bounds, v(16., 0., 20.), v(20., 4., 20.));
    assert_eq!(s.face_count(), 3 + 12 + 6 + 6 + 4);
    // The glTF up axis is adopted when the scene file sets none.
    assert_eq!(s.up(), DVec3::Y);
}

#[test]
fn gltf_references_to_missing_accessors_and_bad_buffer_uris_are_errors() {
    let dir = TempDir::new("gltf-refs");
    // A primitive naming an accessor the document lacks (the glTF crate's own validation
    // indexed it and panicked).
    let p = dir.write(
        "no-accessors.gltf",
        r#"{"asset": {"version": "2.0"}, "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}"#,
    );
    assert_element(
        &load_err(&p),
        &p,
        "mesh 0 primitive 0",
        "refers to accessor 0, and the document has 0",
    );
    // A buffer URI whose percent-encoding decodes to bytes that are not UTF-8 (the
    // crate unwrapped the decoding and panicked).
    let p = dir.write(
        "bad-uri.gltf",
        r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 1, "uri": "%FF"}]}"#,
    );
    assert_element(
        &load_err(&p),
        &p,
        "buffer 0",
        "not valid percent-encoded UTF-8",
    );
    // A buffer URI naming a directory (or a device, a pipe): refused, not read.
    std::fs::create_dir_all(dir.0.join("folder.bin")).unwrap();
    let p = dir.write(
        "folder.gltf",
        r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "folder%2Ebin"}]}"#,
    );
    let e = load_err(&p);
    assert_element(&e, &p, "buffer 0", "not a regular file");
    assert!(e.to_string().contains("folder.bin"), "{e}");
    // A percent-encoded name of a real file is decoded.
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2]));
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {p0}}}, "indices": {i0}}}]}}], "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0"#
    );
    dir.write("sq uare.bin", &g.bin);
    let p = dir.write(
        "spaced.gltf",
        g.json(
            &rest,
            &format!(
                r#"{{"byteLength": {}, "uri": "sq%20uare.bin"}}"#,
                g.bin.len()
            ),
        ),
    );
    assert_eq!(load(&p).face_count(), 1);
}

#[test]
fn gltf_node_matrices_that_are_not_affine_are_errors() {
    let dir = TempDir::new("gltf-affine");
    let mut g = GltfBuffer::default();
    let (p0, i0) = (g.positions(&SQUARE), g.indices(&[0, 1, 2]));
    for (name, last_row) in [("w7", "0, 0, 0, 7"), ("flat", "0, 0, 1, 0")] {
        let rest = format!(
            r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {p0}}}, "indices": {i0}}}]}}], "nodes": [{{"mesh": 0, "matrix": [1, 0, 0, {}, 0, 1, 0, {}, 0, 0, 1, {}, 0, 0, 0, {}]}}], "scenes": [{{"nodes": [0]}}], "scene": 0"#,
            // Column-major: the last row is the fourth entry of each column.
            &last_row[0..1],
            &last_row[3..4],
            &last_row[6..7],
            &last_row[9..10]
        );
        let p = dir.write(&format!("{name}.gltf"), g.gltf_embedded(&rest));
        assert_element(&load_err(&p), &p, "node 0", "not affine");
    }
}

#[test]
fn side_files_that_are_not_regular_files_are_not_read() {
    let dir = TempDir::new("not-regular");
    std::fs::create_dir_all(dir.0.join("colours.mtl")).unwrap();
    let p = dir.write(
        "tri.obj",
        "mtllib colours.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let s = load(&p);
    let messages = s.report().messages.join("\n");
    assert!(messages.contains("not a regular file"), "{messages}");
    // The scene file itself.
    match load_err(&dir.0) {
        Error::Io { .. } | Error::UnsupportedFormat { .. } => {}
        e => panic!("expected an error naming the folder, got {e:?}"),
    }
}

#[test]
fn ply_ascii_lines_with_more_values_than_the_header_are_errors() {
    let dir = TempDir::new("ply-extra");
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                  property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    // Well formed (a trailing blank is not a value): loads.
    let p = dir.write("ok.ply", format!("{header}0 0 0 \n1 0 0\n0 1 0\n3 0 1 2\n"));
    assert_eq!(load(&p).face_count(), 1);
    // A vertex line with two values too many (line 10, the first after the header).
    let p = dir.write(
        "vertex.ply",
        format!("{header}0 0 0 7 7\n1 0 0\n0 1 0\n3 0 1 2\n"),
    );
    assert_at_line(
        &load_err(&p),
        &p,
        10,
        "vertex 0: 5 values on the line, the header's properties take 3",
    );
    // A face line longer than its list.
    let p = dir.write(
        "face.ply",
        format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 2 5\n"),
    );
    assert_at_line(
        &load_err(&p),
        &p,
        13,
        "face 0: 5 values on the line, the header's properties take 4",
    );
}

#[test]
fn ply_headers_declaring_a_name_twice_are_errors() {
    let dir = TempDir::new("ply-twice");
    let body = "0 0 0 0\n1 0 0 0\n0 1 0 0\n3 0 1 2\n";
    let header = |vertex_props: &str, extra: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 3\n{vertex_props}{extra}element face 1\n\
             property list uchar int vertex_indices\nend_header\n{body}"
        )
    };
    // Line 5: the second "x" of the vertex element.
    let p = dir.write(
        "property.ply",
        header(
            "property float x\nproperty float x\nproperty float y\nproperty float z\n",
            "",
        ),
    );
    assert_at_line(&load_err(&p), &p, 5, "property \"x\" is declared twice");
    // The same property name in two elements is fine.
    let p = dir.write(
        "two-elements.ply",
        header(
            "property float x\nproperty float y\nproperty float z\nproperty float w\n",
            "",
        )
        .replace(
            "property list uchar int vertex_indices",
            "property float w\nproperty list uchar int vertex_indices",
        )
        .replace("3 0 1 2", "7 3 0 1 2"),
    );
    assert_eq!(load(&p).face_count(), 1);
    // An element declared twice.
    let p = dir.write(
        "element.ply",
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nelement vertex 0\nend_header\n",
    );
    assert_at_line(&load_err(&p), &p, 5, "element \"vertex\" is declared twice");
}

// ---------------------------------------------------------------------------------
// Findings of the CLI review (F1, F6, F7, F8, F13, F21, F23)

const BOM: &str = "\u{feff}";

/// A byte-order mark at the start of a text file (or a text header) is skipped: it
/// used to hide the first statement (a vertex, an `mtllib`, a `newmtl`) or make an
/// ASCII STL look binary.
#[test]
fn a_byte_order_mark_at_the_start_of_text_files_is_skipped() {
    let dir = TempDir::new("bom");
    // OBJ: the first vertex is kept, so face 0 is the triangle the file means.
    let p = dir.write(
        "bom.obj",
        format!("{BOM}v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n"),
    );
    let s = load(&p);
    assert!(same_cycle(
        &face_polygons(&s, 0)[0],
        &[v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.)]
    ));
    // OBJ whose first line is `mtllib`, and an MTL whose first line is `newmtl`.
    dir.write("m.mtl", format!("{BOM}newmtl red\nKd 1 0 0\n"));
    let p = dir.write(
        "bom_mtllib.obj",
        format!("{BOM}mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n"),
    );
    let s = load(&p);
    assert_eq!(s.objects()[0].face_color(0), [1.0, 0.0, 0.0]);
    assert!(s.report().messages.is_empty(), "{:?}", s.report().messages);
    // ASCII PLY header.
    let p = dir.write("bom.ply", format!("{BOM}{}", ascii_ply(&cube_faces())));
    assert_ply_cube(&load(&p));
    // ASCII STL: read as ASCII, not as a binary file announcing millions of facets.
    let p = dir.write(
        "bom.stl",
        format!("{BOM}{}", ascii_stl("block", &cube_triangles(), "\n")),
    );
    let s = load(&p);
    assert_stl_cube(&s);
    assert_eq!(s.objects()[0].name, "block");
    // glTF JSON (the specification lets readers ignore a BOM).
    let (g, rest) = hierarchy();
    let p = dir.write("bom.gltf", format!("{BOM}{}", g.gltf_embedded(&rest)));
    assert_hierarchy(&load(&p));
    // Scene TOML.
    dir.write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let p = dir.write("bom.toml", format!("{BOM}[[object]]\nmesh = \"tri.obj\"\n"));
    assert_eq!(load(&p).face_count(), 1);
}

/// The usual layout of a multi-material glTF mesh: one POSITION accessor, an index
/// accessor per primitive. Each primitive used to decode (and copy into the mesh) all
/// the vertices again, and the file was refused for asking too much memory.
#[test]
fn gltf_primitives_sharing_one_position_accessor_share_its_vertices() {
    const VERTICES: usize = 20_000;
    const PRIMITIVES: usize = 1000;
    let dir = TempDir::new("gltf-shared");
    let mut g = GltfBuffer::default();
    let points: Vec<[f32; 3]> = (0..VERTICES)
        .map(|i| [i as f32, if i % 3 == 1 { 1.0 } else { 0.0 }, 0.0])
        .collect();
    let pos = g.positions(&points);
    let primitives: Vec<String> = (0..PRIMITIVES)
        .map(|k| {
            let i = (3 * k) as u16;
            let idx = g.indices(&[i, i + 1, i + 2]);
            format!(r#"{{"attributes": {{"POSITION": {pos}}}, "indices": {idx}}}"#)
        })
        .collect();
    let rest = format!(
        r#""meshes": [{{"primitives": [{}]}}], "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0]}}], "scene": 0"#,
        primitives.join(", ")
    );
    dir.write("shared.bin", &g.bin);
    let p = dir.write(
        "shared.gltf",
        g.json(
            &rest,
            &format!(r#"{{"byteLength": {}, "uri": "shared.bin"}}"#, g.bin.len()),
        ),
    );
    let s = load(&p);
    assert_eq!(s.face_count() as usize, PRIMITIVES);
    assert_eq!(s.polygon_count(), PRIMITIVES);
    assert_eq!(
        s.objects()[0].mesh.positions().len(),
        VERTICES,
        "decoded once"
    );
    assert!(same_cycle(
        &face_polygons(&s, 999)[0],
        &[v(2997., 0., 0.), v(2998., 1., 0.), v(2999., 0., 0.)]
    ));
}

/// A coordinate beyond the accepted range is refused where the loader knows the line
/// or element, not later by the scene, which only knew the object.
#[test]
fn coordinates_beyond_the_accepted_range_name_the_file_and_line_or_element() {
    let dir = TempDir::new("range");
    let p = dir.write("big.obj", "v -2e30 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_at_line(
        &load_err(&p),
        &p,
        1,
        "-2e30 is beyond the largest coordinate",
    );
    // 1e31 used to pass the loader and leave the face dropped as a sliver: an empty
    // scene that never mentioned the coordinate.
    let p = dir.write("sliver.obj", "v 0 0 0\nv 1e31 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_at_line(&load_err(&p), &p, 2, "1e31");
    let mut faces = ascii_ply(&cube_faces());
    faces = faces.replacen("1 1 1 255 0 0", "1 1 3e30 255 0 0", 1);
    let p = dir.write("big.ply", faces);
    let line = 1 + ascii_ply(&cube_faces())
        .lines()
        .position(|l| l == "1 1 1 255 0 0")
        .unwrap();
    assert_at_line(&load_err(&p), &p, line, "vertex 7: coordinate 3e30");
    let mut tris = cube_triangles();
    tris[4][2].z = -5e35;
    let p = dir.write("big.stl", binary_stl(b"", &tris));
    assert_element(&load_err(&p), &p, "facet 4", "vertex 2: coordinate -5e35");
    // glTF: in the accessor, and in world space under a node's scale.
    let mut g = GltfBuffer::default();
    let pos = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 4e30, 0.]]);
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}}}]}}], "nodes": [{{"mesh": 0}}]"#
    );
    let p = dir.write("big.gltf", g.gltf_embedded(&rest));
    let e = load_err(&p);
    assert_element(
        &e,
        &p,
        "accessor 0 (POSITION)",
        "element 2 is beyond the largest coordinate",
    );
    assert!(!e.to_string().contains("4e30"), "{e}");
    let mut g = GltfBuffer::default();
    let pos = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]);
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}}}]}}], "nodes": [{{"name": "far", "mesh": 0, "scale": [1e30, 1e30, 1e30]}}]"#
    );
    let p = dir.write("hugescale.gltf", g.gltf_embedded(&rest));
    assert_element(&load_err(&p), &p, "node 0 (far)", "beyond the largest");
}

/// An empty scene says why: the warnings of the loader come with the error.
#[test]
fn empty_scenes_carry_the_warnings_that_explain_them() {
    let dir = TempDir::new("empty-why");
    let empty_message = |p: &Path| match load_err(p) {
        Error::EmptyScene(m) => m,
        e => panic!("expected an empty scene, got {e:?}"),
    };
    let mut g = GltfBuffer::default();
    let pos = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]);
    let prim = |mode: u32| format!(r#"{{"attributes": {{"POSITION": {pos}}}, "mode": {mode}}}"#);
    // A node hidden by a zero scale.
    let rest = format!(
        r#""meshes": [{{"primitives": [{}]}}], "nodes": [{{"name": "hidden", "mesh": 0, "scale": [0, 1, 1]}}]"#,
        prim(4)
    );
    let m = empty_message(&dir.write("zeroscale.gltf", g.gltf_embedded(&rest)));
    assert!(
        m.contains("singular transform") && m.contains("hidden"),
        "{m}"
    );
    // Only lines and points.
    let rest = format!(
        r#""meshes": [{{"primitives": [{}, {}]}}], "nodes": [{{"mesh": 0}}]"#,
        prim(1),
        prim(0)
    );
    let m = empty_message(&dir.write("lines.gltf", g.gltf_embedded(&rest)));
    assert!(
        m.contains("2 primitive(s) skipped") && m.contains("Lines"),
        "{m}"
    );
    // A binary STL whose header says 0 facets, followed by facets.
    let mut bytes = binary_stl(b"", &cube_triangles()[..2]);
    bytes[80..84].copy_from_slice(&0u32.to_le_bytes());
    let m = empty_message(&dir.write("count0.stl", bytes));
    assert!(m.contains("100 bytes after the 0 facets"), "{m}");
    // Only degenerate faces.
    let m = empty_message(&dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"));
    assert!(m.contains("1 degenerate face(s)"), "{m}");
}

/// A glTF node graph with a cycle and no scene used to yield an empty scene without a
/// word (no node was parentless, so none was a root).
#[test]
fn gltf_node_cycles_are_errors_even_without_a_scene() {
    let dir = TempDir::new("gltf-cycle");
    let mut g = GltfBuffer::default();
    let pos = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]);
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}}}]}}], "nodes": [{{"children": [1]}}, {{"children": [0], "mesh": 0}}]"#
    );
    let p = dir.write("cycle.gltf", g.gltf_embedded(&rest));
    assert_element(&load_err(&p), &p, "node 0", "cycle");
}

/// Errors about external glTF buffers name the glTF file and the buffer; remote URIs
/// are refused as such instead of being looked up as local paths.
#[test]
fn gltf_buffer_errors_name_the_gltf_and_the_buffer_and_remote_uris_are_refused() {
    let dir = TempDir::new("gltf-buffers");
    let (g, rest) = hierarchy();
    for uri in [
        "http://example.com/x.bin",
        "https://example.com/x.bin",
        "ftp://h/x.bin",
    ] {
        let p = dir.write(
            "remote.gltf",
            g.json(
                &rest,
                &format!(r#"{{"byteLength": {}, "uri": "{uri}"}}"#, g.bin.len()),
            ),
        );
        let e = load_err(&p);
        assert_element(
            &e,
            &p,
            &format!("buffer 0 (uri \"{uri}\")"),
            "remote files are not read",
        );
    }
    let p = dir.write(
        "missing.gltf",
        g.json(
            &rest,
            &format!(r#"{{"byteLength": {}, "uri": "missing.bin"}}"#, g.bin.len()),
        ),
    );
    let e = load_err(&p);
    assert_element(&e, &p, "buffer 0 (uri \"missing.bin\")", "missing.bin");
}

/// Warnings that repeat are aggregated, and a warning does not name the file loaded
/// (the caller prints it once); a scene file's report names the mesh file.
#[test]
fn warnings_are_aggregated_and_do_not_repeat_the_file_name() {
    let dir = TempDir::new("warnings");
    dir.write("odd.mtl", "newmtl known\nKd 0 1 0\n");
    let mut text = String::from("mtllib odd.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for k in 0..1000 {
        text.push_str(&format!("usemtl m{k}\nf 1 2 3\n"));
    }
    let p = dir.write("manymtl.obj", &text);
    let s = load(&p);
    let messages = &s.report().messages;
    assert_eq!(messages.len(), 1, "{messages:?}");
    let m = &messages[0];
    assert!(m.starts_with("1000 unknown material(s)"), "{m}");
    assert!(
        m.contains("\"m0\" (line 5)") && m.contains("and 997 more"),
        "{m}"
    );
    assert!(!m.contains("manymtl.obj"), "the caller names the file: {m}");
    // Through a scene file, the warning names the mesh file (once).
    let t = dir.write("scene.toml", "[[object]]\nmesh = \"manymtl.obj\"\n");
    let s = load(&t);
    let m = &s.report().messages[0];
    assert_eq!(m.matches("manymtl.obj").count(), 1, "{m}");
    assert!(m.contains("1000 unknown material(s)"), "{m}");
    // Malformed MTL lines: one warning naming the library.
    dir.write(
        "bad.mtl",
        "newmtl a\nKd x\nKd 1 2\nKd spectral f.rfl\nKd 1 1 1 1\n",
    );
    let p = dir.write(
        "badmtl.obj",
        "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    let s = load(&p);
    let messages = &s.report().messages;
    assert_eq!(messages.len(), 1, "{messages:?}");
    assert!(
        messages[0].contains("bad.mtl: 4 Kd line(s)"),
        "{messages:?}"
    );
    assert!(messages[0].contains("line 2: malformed"), "{messages:?}");
}

/// An ASCII STL holding several solids yields them all (the second was dropped).
#[test]
fn ascii_stl_with_several_solids_loads_them_all() {
    let dir = TempDir::new("stl-solids");
    let tris = cube_triangles();
    let text = format!(
        "{}{}",
        ascii_stl("first", &tris[..2], "\n"),
        ascii_stl("second", &tris[2..], "\n")
    );
    let s = load(&dir.write("two.stl", &text));
    let names: Vec<&str> = s.objects().iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["first", "second"]);
    assert_eq!(s.face_count(), 12);
    for (k, t) in tris.iter().enumerate() {
        assert_eq!(face_polygons(&s, k as u32), vec![t.to_vec()], "facet {k}");
    }
    // Errors in the second solid name it, and count facets across the file.
    let bad = text.replacen("vertex 1 1 1", "vertex 1 x 1", 1);
    let at = tris
        .iter()
        .position(|t| t.contains(&v(1., 1., 1.)))
        .unwrap();
    assert!(at >= 2, "the first (1, 1, 1) is in the second solid");
    let line = bad
        .lines()
        .position(|l| l.contains("vertex 1 x 1"))
        .unwrap()
        + 1;
    let p = dir.write("bad.stl", bad);
    assert_at_line(
        &load_err(&p),
        &p,
        line,
        &format!("solid 1 (\"second\") facet {at}: \"x\" is not a number"),
    );
    // Text after the last endsolid that is not a solid is a warning.
    let s = load(&dir.write(
        "junk.stl",
        format!("{}garbage\n", ascii_stl("a", &tris, "\n")),
    ));
    assert_eq!(s.face_count(), 12);
    let messages = s.report().messages.join("\n");
    assert!(messages.contains("after the last endsolid"), "{messages}");
}

/// A PLY face element with both `vertex_indices` and `vertex_index` lists used to join
/// them into one polygon.
#[test]
fn ply_faces_with_two_index_lists_are_refused() {
    let dir = TempDir::new("ply-both");
    let p = dir.write(
        "both.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nproperty list uchar int vertex_index\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2 3 1 3 2\n",
    );
    assert_at_line(
        &load_err(&p),
        &p,
        9,
        "both a vertex_indices and a vertex_index",
    );
}

/// A scene listing the same node twice places it once (it was drawn twice, each face
/// fighting its copy).
#[test]
fn gltf_scene_listing_a_node_twice_places_it_once() {
    let dir = TempDir::new("gltf-dup");
    let mut g = GltfBuffer::default();
    let pos = g.positions(&[[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]]);
    let rest = format!(
        r#""meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}}}}}]}}], "nodes": [{{"mesh": 0}}], "scenes": [{{"nodes": [0, 0]}}], "scene": 0"#
    );
    let s = load(&dir.write("dup.gltf", g.gltf_embedded(&rest)));
    assert_eq!(s.objects().len(), 1);
    let messages = s.report().messages.join("\n");
    assert!(
        messages.contains("listed again") && messages.contains("node 0"),
        "{messages}"
    );
}

// ---------------------------------------------------------------------------------
// Issue 21: loader detection and messages

/// ASCII STL keywords in any case, after white space or a byte-order mark, are read as
/// ASCII (an upper-case `SOLID` was read as a binary file announcing 1347374924 facets).
#[test]
fn stl_ascii_keywords_in_any_case_are_ascii() {
    let dir = TempDir::new("stl-case");
    let tris = cube_triangles();
    let lower = ascii_stl("block", &tris, "\n");
    let mixed: String = lower
        .split('\n')
        .map(|l| {
            // Every keyword capitalised: "Solid", "Facet Normal", "Outer Loop", ...
            l.split(' ')
                .map(|w| {
                    let mut c = w.chars();
                    c.next().map_or(String::new(), |f| {
                        f.to_ascii_uppercase().to_string() + c.as_str()
                    })
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let cases = [
        (
            "upper.stl",
            lower.to_uppercase().replace("SOLID BLOCK", "SOLID block"),
        ),
        ("mixed.stl", mixed.replace("Solid Block", "Solid block")),
        (
            "blank.stl",
            format!(
                "  \n\t {}",
                lower.to_uppercase().replace("SOLID BLOCK", "SOLID block")
            ),
        ),
        (
            "bom.stl",
            format!(
                "{BOM}\r\n{}",
                lower
                    .replace("solid block", "SoLiD block")
                    .replace('\n', "\r\n")
            ),
        ),
    ];
    for (name, text) in cases {
        let s = load(&dir.write(name, &text));
        assert_stl_cube(&s);
        assert_eq!(s.objects()[0].name, "block", "{name}");
    }
    // Neither form: the error says what either must look like and what the file has.
    let p = dir.write("text.stl", "hello, this is not a mesh\n");
    let e = load_err(&p);
    assert_element(&e, &p, "header", "not an STL file");
    let text = e.to_string();
    assert!(text.contains("starts with \"solid\""), "{text}");
    assert!(text.contains("84-byte header"), "{text}");
    assert!(text.contains("starts with \"hello, this is n\""), "{text}");
    // "solidify" is not the keyword.
    let p = dir.write("solidify.stl", "solidify\n");
    assert_element(&load_err(&p), &p, "header", "not an STL file");
}

/// Many solids, one facet each: all are loaded, in order, with face ids following the
/// file (the loader used to re-count the faces of every earlier solid at each new one,
/// 41 s for 200,000 solids).
#[test]
fn stl_with_many_solids_loads_all_with_file_order_ids() {
    let dir = TempDir::new("stl-many");
    let n = 2000;
    let tri = |k: usize| {
        let x = k as f64;
        [v(x, 0., 0.), v(x + 1., 0., 0.), v(x, 1., 0.)]
    };
    let mut text = String::new();
    for k in 0..n {
        text.push_str(&ascii_stl(&format!("part{k}"), &[tri(k)], "\n"));
    }
    let s = load(&dir.write("many.stl", &text));
    assert_eq!(s.objects().len(), n);
    assert_eq!(s.face_count() as usize, n);
    for k in [0, 1, 2, 999, 1000, n - 1] {
        assert_eq!(s.objects()[k].name, format!("part{k}"));
        assert_eq!(
            face_polygons(&s, k as u32),
            vec![tri(k).to_vec()],
            "facet {k}"
        );
    }
    // An error in the last solid names its line, the solid and the file-wide facet.
    let bad = text.replacen(
        &format!("vertex {} 1 0", n - 1),
        &format!("vertex {} 1", n - 1),
        1,
    );
    let line = bad
        .lines()
        .position(|l| l.trim() == format!("vertex {} 1", n - 1))
        .unwrap()
        + 1;
    let p = dir.write("bad.stl", bad);
    assert_at_line(
        &load_err(&p),
        &p,
        line,
        &format!(
            "solid {} (\"part{}\") facet {}: a vertex needs x, y and z; found 2",
            n - 1,
            n - 1,
            n - 1
        ),
    );
}

/// A `.glb` whose magic number is wrong is not parsed as JSON: the error names the
/// bytes found, in hex, and the magic expected; a file that is neither JSON nor GLB
/// says so whatever its extension; a GLB named `.gltf` loads.
#[test]
fn gltf_containers_are_told_by_their_content() {
    let dir = TempDir::new("gltf-magic");
    let (g, rest) = hierarchy();
    let mut glb = g.glb(&rest);
    assert_hierarchy(&load(&dir.write("good.glb", &glb)));
    assert_hierarchy(&load(&dir.write("binary.gltf", &glb)));
    // A JSON glTF named .glb is read as JSON.
    assert_hierarchy(&load(&dir.write("json.glb", g.gltf_embedded(&rest))));
    glb[..4].copy_from_slice(&[0xDE, 0xAD, 0xBE, 0xEF]);
    let p = dir.write("bad.glb", &glb);
    let e = load_err(&p);
    assert_element(&e, &p, "GLB header", "the magic number is DE AD BE EF");
    assert!(
        e.to_string().contains("expected 67 6C 54 46 (\"glTF\")"),
        "{e}"
    );
    let p = dir.write("bad.gltf", &glb);
    let e = load_err(&p);
    assert_element(&e, &p, "document", "starts with the bytes DE AD BE EF");
    assert!(e.to_string().contains("JSON"), "{e}");
    // Lower-case magic, and text that is not JSON.
    glb[..4].copy_from_slice(b"gltf");
    let p = dir.write("lower.glb", &glb);
    assert_element(&load_err(&p), &p, "GLB header", "67 6C 74 66");
    let p = dir.write("text.glb", "not a model");
    assert_element(&load_err(&p), &p, "GLB header", "6E 6F 74 20");
}

/// Asserts that an error reads as a sentence: no Rust debug structures, one line.
fn assert_readable(e: &Error) {
    let text = e.to_string();
    for artefact in [
        "{", "}", "Some(", "None", "Err(", "Ok(", "\n", "\t", "Line ",
    ] {
        assert!(!text.contains(artefact), "{artefact:?} in \"{text}\"");
    }
}

/// Every PLY error is a sentence naming the line (header, ASCII body) or the element
/// (binary body), never a debug print of the parser's structures.
#[test]
fn ply_errors_are_sentences_naming_the_line_or_element() {
    let dir = TempDir::new("ply-sentences");
    let vertex = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let ascii =
        |header: &str, body: &str| format!("ply\nformat ascii 1.0\n{header}end_header\n{body}");
    // (file, text, line, what the message must say)
    let cases: Vec<(&str, String, usize, &str)> = vec![
        (
            "magic.ply",
            "PLY\nformat ascii 1.0\nend_header\n".into(),
            1,
            "first line must be \"ply\"",
        ),
        (
            "format.ply",
            "ply\nformat text 1.0\nend_header\n".into(),
            2,
            "format \"text\"",
        ),
        (
            "version.ply",
            "ply\nformat ascii 2.0\nend_header\n".into(),
            2,
            "version \"2.0\"",
        ),
        (
            "noformat.ply",
            format!("ply\n{vertex}end_header\n"),
            6,
            "no \"format\" line",
        ),
        (
            "keyword.ply",
            ascii(&format!("{vertex}elemnt face 1\n"), body),
            7,
            "unknown keyword \"elemnt\"",
        ),
        (
            "type.ply",
            ascii("element vertex 3\nproperty flaot x\n", body),
            4,
            "unknown type \"flaot\"",
        ),
        (
            "count.ply",
            ascii("element vertex three\n", body),
            3,
            "count \"three\"",
        ),
        (
            "negative.ply",
            ascii("element vertex -3\n", body),
            3,
            "not a non-negative integer",
        ),
        (
            "orphan.ply",
            ascii("property float x\n", body),
            3,
            "a property before any element",
        ),
        (
            "listcount.ply",
            ascii(
                &format!("{vertex}element face 1\nproperty list float int vertex_indices\n"),
                body,
            ),
            8,
            "expected an integer type",
        ),
        (
            "noend.ply",
            format!("ply\nformat ascii 1.0\n{vertex}"),
            6,
            "ends before \"end_header\"",
        ),
        (
            "value.ply",
            ascii(
                &format!("{vertex}{face}"),
                "0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n",
            ),
            12,
            "vertex 2: property y: \"one\" is not a number",
        ),
        (
            "short.ply",
            ascii(&format!("{vertex}{face}"), "0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
            11,
            "vertex 1: the line ends after 2 value(s)",
        ),
        (
            "uchar.ply",
            ascii(
                &format!("{vertex}{face}"),
                "0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n",
            ),
            13,
            "300 is out of the range of a uchar",
        ),
        (
            "index.ply",
            ascii(
                &format!("{vertex}{face}"),
                "0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n",
            ),
            13,
            "\"2.5\" is not an integer",
        ),
        (
            "list.ply",
            ascii(&format!("{vertex}{face}"), "0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"),
            13,
            "face 0: the line ends after 4 value(s)",
        ),
    ];
    for (name, text, line, needle) in cases {
        let p = dir.write(name, text);
        let e = load_err(&p);
        assert_at_line(&e, &p, line, needle);
        assert_readable(&e);
    }
    // Binary bodies name the element.
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
                  property float y\nproperty float z\nelement face 1\n\
                  property list int int vertex_indices\nend_header\n";
    let mut b = header.as_bytes().to_vec();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        b.extend(c.to_le_bytes());
    }
    let mut negative = b.clone();
    negative.extend((-3i32).to_le_bytes());
    let p = dir.write("negative_list.ply", &negative);
    let e = load_err(&p);
    assert_element(&e, &p, "face 0", "negative length -3");
    assert_readable(&e);
    let mut huge = b.clone();
    huge.extend(i32::MAX.to_le_bytes());
    huge.extend([0u8; 12]);
    let p = dir.write("huge_list.ply", &huge);
    let e = load_err(&p);
    assert_element(&e, &p, "face 0", "truncated");
    assert_readable(&e);
    let p = dir.write("cut.ply", &b[..b.len() - 6]);
    let e = load_err(&p);
    assert_element(&e, &p, "vertex 2", "truncated");
    assert_readable(&e);
}

/// Warnings about a mesh placed by a scene file name the mesh file (the count of
/// dropped faces used to appear under the scene file's name alone).
#[test]
fn toml_scene_mesh_warnings_name_the_mesh_file() {
    let dir = TempDir::new("toml-warnings");
    let mesh = dir.write(
        "flat.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 4 2\nusemtl nowhere\nf 1 2 3\n",
    );
    dir.write("good.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let scene = dir.write(
        "scene.toml",
        "[[object]]\nmesh = \"flat.obj\"\n\n[[object]]\nmesh = \"good.obj\"\ntranslate = [5, 0, 0]\n",
    );
    let s = load(&scene);
    assert_eq!(s.report().degenerate_faces, 2, "the counts stay");
    let warnings = s.report().warnings();
    let named = mesh.display().to_string();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    for w in &warnings {
        assert!(
            w.starts_with(&format!("{named}: ")),
            "{w:?} should name {named}"
        );
    }
    assert!(
        warnings.iter().any(|w| w.contains("2 degenerate face(s)")),
        "{warnings:?}"
    );
    assert!(
        warnings.iter().any(|w| w.contains("unknown material")),
        "{warnings:?}"
    );
    // The same mesh loaded directly: the caller names it, the warnings do not.
    let direct = load(&mesh).report().warnings();
    assert!(direct.iter().all(|w| !w.contains("flat.obj")), "{direct:?}");
}
