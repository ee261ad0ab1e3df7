//! Linearity of every loader: each input shape is generated at N and 4N items, loaded
//! (`load_file`, as the CLI does), and the ratio of the two times printed. A linear
//! loader gives about 4; a quadratic one about 16. Times are the loading thread's CPU
//! time (Linux), so that other processes on a shared machine do not count; cache
//! effects still push ratios of the larger inputs a little above 4.
//!
//! `cargo bench -p obscura --bench loaders` runs the full sizes (inputs of 1 to 50 MB,
//! best of 5 runs each, N and 4N in turn); under `cargo test` the same shapes run at a tiny size, as a
//! smoke test. `cargo bench -p obscura --bench loaders -- NAME` runs the shapes whose
//! name contains NAME; `OBSCURA_BENCH_SCALE=4` multiplies every N by 4. Inputs are written to a temporary folder and removed after.
//!
//! Shapes: what a hostile or merely unusual file may have many of (objects, groups,
//! solids, header lines, materials, nodes, nesting, long lines, repeated statements).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A generated input: the file to load first, then side files (`(name, contents)`).
type Files = Vec<(String, Vec<u8>)>;

struct Shape {
    name: &'static str,
    /// Items at the base size N.
    n: usize,
    make: fn(usize) -> Files,
}

fn one(name: &str, text: String) -> Files {
    vec![(name.to_string(), text.into_bytes())]
}

// ---------------------------------------------------------------------------------
// STL

fn stl_facet(s: &mut String, k: usize) {
    let x = k as f64;
    let _ = write!(
        s,
        "facet normal 0 0 1\nouter loop\nvertex {x} 0 0\nvertex {} 0 0\nvertex {x} 1 0\nendloop\nendfacet\n",
        x + 1.0
    );
}

fn stl_many_solids(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let _ = writeln!(s, "solid part{k}");
        stl_facet(&mut s, k);
        let _ = writeln!(s, "endsolid part{k}");
    }
    one("solids.stl", s)
}

fn stl_one_solid_upper_case(n: usize) -> Files {
    let mut s = String::from("SOLID big\n");
    for k in 0..n {
        stl_facet(&mut s, k);
    }
    s.push_str("ENDSOLID big\n");
    one("upper.stl", s.to_uppercase())
}

fn stl_binary(n: usize) -> Files {
    let mut b = vec![0u8; 80];
    b.extend((n as u32).to_le_bytes());
    for k in 0..n {
        let x = k as f32;
        b.extend([0u8; 12]);
        for c in [x, 0.0, 0.0, x + 1.0, 0.0, 0.0, x, 1.0, 0.0] {
            b.extend(c.to_le_bytes());
        }
        b.extend([0u8; 2]);
    }
    vec![("binary.stl".into(), b)]
}

// ---------------------------------------------------------------------------------
// PLY

fn ply_tri_header() -> &'static str {
    "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
     element face 1\nproperty list uchar int vertex_indices\n"
}

fn ply_many_header_elements(n: usize) -> Files {
    let mut s = String::from("ply\nformat ascii 1.0\n");
    for k in 0..n {
        let _ = writeln!(s, "element extra{k} 0");
    }
    s.push_str(ply_tri_header());
    s.push_str("end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    one("elements.ply", s)
}

fn ply_many_properties(n: usize) -> Files {
    let mut s = String::from("ply\nformat ascii 1.0\n");
    s.push_str(ply_tri_header().split("element face").next().unwrap());
    for k in 0..n {
        let _ = writeln!(s, "property uchar p{k}");
    }
    s.push_str("element face 1\nproperty list uchar int vertex_indices\nend_header\n");
    let zeros = " 0".repeat(n);
    for v in ["0 0 0", "1 0 0", "0 1 0"] {
        let _ = writeln!(s, "{v}{zeros}");
    }
    s.push_str("3 0 1 2\n");
    one("properties.ply", s)
}

fn ply_ascii_faces(n: usize) -> Files {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
         property float z\nelement face {n}\nproperty list uchar int vertex_indices\nend_header\n",
        n + 2
    );
    for k in 0..n + 2 {
        let _ = writeln!(s, "{} {} 0", k / 2, k % 2);
    }
    for k in 0..n {
        let _ = writeln!(s, "3 {k} {} {}", k + 1, k + 2);
    }
    one("faces.ply", s)
}

fn ply_binary_faces(n: usize) -> Files {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nelement face {n}\n\
         property list uchar uint vertex_indices\nend_header\n",
        n + 2
    )
    .into_bytes();
    for k in 0..n + 2 {
        for c in [(k / 2) as f32, (k % 2) as f32, 0.0] {
            b.extend(c.to_le_bytes());
        }
    }
    for k in 0..n as u32 {
        b.push(3);
        for i in [k, k + 1, k + 2] {
            b.extend(i.to_le_bytes());
        }
    }
    vec![("binary.ply".into(), b)]
}

fn ply_one_long_face(n: usize) -> Files {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty double x\nproperty double y\n\
         property double z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n"
    );
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        let _ = writeln!(s, "{} {} 0", a.cos(), a.sin());
    }
    let _ = write!(s, "{n}");
    for k in 0..n {
        let _ = write!(s, " {k}");
    }
    s.push('\n');
    one("polygon.ply", s)
}

// ---------------------------------------------------------------------------------
// OBJ and MTL

fn obj_triangles(n: usize, per: impl Fn(&mut String, usize)) -> String {
    let mut s = String::new();
    for k in 0..n {
        per(&mut s, k);
        let x = k as f64;
        let _ = write!(s, "v {x} 0 0\nv {} 0 0\nv {x} 1 0\nf -3 -2 -1\n", x + 1.0);
    }
    s
}

fn obj_faces(n: usize) -> Files {
    one("faces.obj", obj_triangles(n, |_, _| {}))
}

fn obj_many_objects(n: usize) -> Files {
    one(
        "objects.obj",
        obj_triangles(n, |s, k| {
            let _ = writeln!(s, "o part{k}");
        }),
    )
}

fn obj_many_groups_without_faces(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let _ = writeln!(s, "g group{k}");
    }
    s.push_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    one("groups.obj", s)
}

/// N objects each switching to its own material of an N-material library.
fn obj_objects_and_materials(n: usize) -> Files {
    let mut mtl = String::new();
    for k in 0..n {
        let _ = writeln!(mtl, "newmtl m{k}\nKd 0.5 0.5 0.5");
    }
    let obj = obj_triangles(n, |s, k| {
        if k == 0 {
            s.push_str("mtllib lib.mtl\n");
        }
        let _ = writeln!(s, "o part{k}\nusemtl m{k}");
    });
    vec![
        ("materials.obj".into(), obj.into_bytes()),
        ("lib.mtl".into(), mtl.into_bytes()),
    ]
}

/// One object switching material at every face, among N unknown materials.
fn obj_usemtl_switches(n: usize) -> Files {
    one(
        "usemtl.obj",
        obj_triangles(n, |s, k| {
            let _ = writeln!(s, "usemtl m{}", k % 7);
        }),
    )
}

/// The same library named on N `mtllib` lines.
fn obj_repeated_mtllib(n: usize) -> Files {
    let mut mtl = String::new();
    for k in 0..1000 {
        let _ = writeln!(mtl, "newmtl m{k}\nKd 1 0 0");
    }
    let mut s = "mtllib lib.mtl\n".repeat(n);
    s.push_str("usemtl m1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    vec![
        ("mtllib.obj".into(), s.into_bytes()),
        ("lib.mtl".into(), mtl.into_bytes()),
    ]
}

/// One polygon of N corners on one long line.
fn obj_one_long_face(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        let _ = writeln!(s, "v {} {} 0", a.cos(), a.sin());
    }
    s.push('f');
    for k in 1..=n {
        let _ = write!(s, " {k}");
    }
    s.push('\n');
    one("polygon.obj", s)
}

/// One face statement continued over N lines with `\`.
fn obj_continued_lines(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::TAU;
        let _ = writeln!(s, "v {} {} 0", a.cos(), a.sin());
    }
    s.push('f');
    for k in 1..=n {
        let _ = writeln!(s, " {k} \\");
    }
    s.push('\n');
    one("continued.obj", s)
}

// ---------------------------------------------------------------------------------
// glTF

/// A glTF with one triangle mesh (embedded buffer) and the given nodes and scene.
fn gltf_with(meshes: usize, nodes: &str, scene_nodes: &str) -> String {
    let mut bytes = Vec::new();
    for c in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        bytes.extend(c.to_le_bytes());
    }
    let b64 = base64(&bytes);
    let mut mesh_list = String::new();
    for k in 0..meshes {
        if k > 0 {
            mesh_list.push(',');
        }
        mesh_list.push_str(r#"{"primitives":[{"attributes":{"POSITION":0}}]}"#);
    }
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{scene_nodes}]}}],
"nodes":[{nodes}],"meshes":[{mesh_list}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
    )
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let v = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(v >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

fn list(n: usize, item: impl Fn(usize) -> String) -> String {
    (0..n).map(item).collect::<Vec<_>>().join(",")
}

fn gltf_many_nodes(n: usize) -> Files {
    let nodes = list(n, |k| format!(r#"{{"mesh":0,"translation":[{k},0,0]}}"#));
    one(
        "nodes.gltf",
        gltf_with(1, &nodes, &list(n, |k| k.to_string())),
    )
}

fn gltf_many_meshes(n: usize) -> Files {
    let nodes = list(n, |k| format!(r#"{{"mesh":{k},"translation":[{k},0,0]}}"#));
    one(
        "meshes.gltf",
        gltf_with(n, &nodes, &list(n, |k| k.to_string())),
    )
}

/// A chain of N nodes, each the child of the previous one.
fn gltf_deep_nesting(n: usize) -> Files {
    let nodes = list(n, |k| {
        if k + 1 < n {
            format!(
                r#"{{"mesh":0,"translation":[1,0,0],"children":[{}]}}"#,
                k + 1
            )
        } else {
            r#"{"mesh":0,"translation":[1,0,0]}"#.to_string()
        }
    });
    one("deep.gltf", gltf_with(1, &nodes, "0"))
}

/// One mesh of N primitives sharing one accessor.
fn gltf_many_primitives(n: usize) -> Files {
    let prims = list(n, |_| r#"{"attributes":{"POSITION":0}}"#.to_string());
    let text = gltf_with(1, r#"{"mesh":0}"#, "0").replace(
        r#"{"primitives":[{"attributes":{"POSITION":0}}]}"#,
        &format!(r#"{{"primitives":[{prims}]}}"#),
    );
    one("primitives.gltf", text)
}

// ---------------------------------------------------------------------------------
// TOML scenes

fn toml_many_primitives(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let _ = writeln!(
            s,
            "[[object]]\nprimitive = \"box\"\ntranslate = [{}, 0, 0]\n",
            2 * k
        );
    }
    one("boxes.toml", s)
}

/// N objects each referencing its own mesh file.
fn toml_many_mesh_files(n: usize) -> Files {
    let mut s = String::new();
    let mut files = Vec::new();
    for k in 0..n {
        let _ = writeln!(
            s,
            "[[object]]\nmesh = \"m{k}.obj\"\ntranslate = [{}, 0, 0]\n",
            2 * k
        );
        files.push((
            format!("m{k}.obj"),
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ));
    }
    files.insert(0, ("files.toml".into(), s.into_bytes()));
    files
}

/// N objects placing the same mesh file.
fn toml_one_mesh_placed_often(n: usize) -> Files {
    let mut s = String::new();
    for k in 0..n {
        let _ = writeln!(
            s,
            "[[object]]\nmesh = \"tri.obj\"\ntranslate = [{}, 0, 0]\n",
            2 * k
        );
    }
    vec![
        ("placed.toml".into(), s.into_bytes()),
        (
            "tri.obj".into(),
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
    ]
}

// ---------------------------------------------------------------------------------

const SHAPES: &[Shape] = &[
    Shape {
        name: "stl ascii: solids",
        n: 50_000,
        make: stl_many_solids,
    },
    Shape {
        name: "stl ascii: facets of one SOLID",
        n: 100_000,
        make: stl_one_solid_upper_case,
    },
    Shape {
        name: "stl binary: facets",
        n: 125_000,
        make: stl_binary,
    },
    Shape {
        name: "ply: header elements",
        n: 200_000,
        make: ply_many_header_elements,
    },
    Shape {
        name: "ply: header properties",
        n: 100_000,
        make: ply_many_properties,
    },
    Shape {
        name: "ply ascii: faces",
        n: 150_000,
        make: ply_ascii_faces,
    },
    Shape {
        name: "ply binary: faces",
        n: 400_000,
        make: ply_binary_faces,
    },
    Shape {
        name: "ply: corners of one face",
        n: 250_000,
        make: ply_one_long_face,
    },
    Shape {
        name: "obj: faces",
        n: 150_000,
        make: obj_faces,
    },
    Shape {
        name: "obj: objects",
        n: 75_000,
        make: obj_many_objects,
    },
    Shape {
        name: "obj: groups without faces",
        n: 500_000,
        make: obj_many_groups_without_faces,
    },
    Shape {
        name: "obj: objects x materials",
        n: 40_000,
        make: obj_objects_and_materials,
    },
    Shape {
        name: "obj: usemtl switches",
        n: 150_000,
        make: obj_usemtl_switches,
    },
    Shape {
        name: "obj: repeated mtllib",
        n: 100_000,
        make: obj_repeated_mtllib,
    },
    Shape {
        name: "obj: corners of one face",
        n: 250_000,
        make: obj_one_long_face,
    },
    Shape {
        name: "obj: continued lines",
        n: 250_000,
        make: obj_continued_lines,
    },
    Shape {
        name: "gltf: nodes",
        n: 100_000,
        make: gltf_many_nodes,
    },
    Shape {
        name: "gltf: meshes",
        n: 30_000,
        make: gltf_many_meshes,
    },
    Shape {
        name: "gltf: nesting depth",
        n: 80_000,
        make: gltf_deep_nesting,
    },
    Shape {
        name: "gltf: primitives of one mesh",
        n: 100_000,
        make: gltf_many_primitives,
    },
    Shape {
        name: "toml: primitives",
        n: 20_000,
        make: toml_many_primitives,
    },
    Shape {
        name: "toml: mesh files",
        n: 4_000,
        make: toml_many_mesh_files,
    },
    Shape {
        name: "toml: one mesh placed often",
        n: 10_000,
        make: toml_one_mesh_placed_often,
    },
];

/// Writes the files of one input in `dir`, returning the first one's path.
fn write(dir: &Path, files: &Files) -> PathBuf {
    for (name, contents) in files {
        std::fs::write(dir.join(name), contents).expect("write bench input");
    }
    dir.join(&files[0].0)
}

/// The CPU time this thread has run, in milliseconds, where the system says
/// (`/proc/thread-self/schedstat` on Linux): loading is single-threaded, and on a
/// shared machine wall time measures the other processes too.
fn cpu_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = stat.split_ascii_whitespace().next()?.parse().ok()?;
    Some(ns / 1e6)
}

/// The time of one load, in milliseconds (CPU time where available, else wall time).
fn time(path: &Path) -> f64 {
    {
        let cpu = cpu_ms();
        let start = Instant::now();
        let scene = obscura::scene::load::load_file(path)
            .unwrap_or_else(|e| panic!("bench input {} should load: {e}", path.display()));
        let wall = start.elapsed().as_secs_f64() * 1e3;
        let ms = match (cpu, cpu_ms()) {
            (Some(a), Some(b)) => b - a,
            _ => wall,
        };
        drop(scene);
        ms
    }
}

/// Best times of `runs` loads of the N and the 4N input, run in turn (so that a change
/// in the machine's load affects both), and their sizes in bytes.
fn time_pair(dir: &Path, small: &Files, large: &Files, runs: usize) -> [(f64, usize); 2] {
    let mut out = [(f64::INFINITY, 0); 2];
    let mut paths = Vec::new();
    for (k, files) in [small, large].into_iter().enumerate() {
        let sub = dir.join(k.to_string());
        std::fs::create_dir_all(&sub).expect("temp dir");
        paths.push(write(&sub, files));
        out[k].1 = files.iter().map(|(_, c)| c.len()).sum();
    }
    for _ in 0..runs {
        for (k, path) in paths.iter().enumerate() {
            out[k].0 = out[k].0.min(time(path));
        }
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // `cargo bench` passes --bench; anything else (cargo test) is a smoke run.
    let full = args.iter().any(|a| a == "--bench");
    let filter = args.iter().find(|a| !a.starts_with('-'));
    // OBSCURA_BENCH_SCALE=k multiplies every N by k (to tell cache effects, which fade,
    // from superlinear work, which grows).
    let scale: usize = std::env::var("OBSCURA_BENCH_SCALE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let dir = std::env::temp_dir().join(format!("obscura-bench-loaders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    println!(
        "{:<32} {:>8} {:>9} {:>9} {:>10} {:>10} {:>6}",
        "shape", "N", "MB(N)", "MB(4N)", "ms(N)", "ms(4N)", "ratio"
    );
    if cpu_ms().is_none() {
        println!("(wall-clock times: this system does not give a thread's CPU time)");
    }
    let mut worst: f64 = 0.0;
    for shape in SHAPES {
        if filter.is_some_and(|f| !shape.name.contains(f.as_str())) {
            continue;
        }
        let n = if full { shape.n * scale } else { 50 };
        let runs = if full { 5 } else { 1 };
        let [(t1, b1), (t4, b4)] = time_pair(&dir, &(shape.make)(n), &(shape.make)(4 * n), runs);
        let ratio = t4 / t1;
        worst = worst.max(ratio);
        println!(
            "{:<32} {n:>8} {:>9.2} {:>9.2} {t1:>10.2} {t4:>10.2} {ratio:>6.2}",
            shape.name,
            b1 as f64 / 1e6,
            b4 as f64 / 1e6,
        );
        // Side files of different shapes must not mix.
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
    }
    let _ = std::fs::remove_dir_all(&dir);
    if full {
        println!("worst ratio {worst:.2} (linear: about 4, quadratic: about 16)");
    }
}
