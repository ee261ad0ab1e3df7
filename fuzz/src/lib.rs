//! Shared checks for the obscura loader fuzz targets: a loaded file must hold finite
//! positions and transforms, and the scene built from it must be framed by its
//! default camera and rendered. Inputs that are accepted but cannot be framed or
//! rendered are saved under `findings/soft/` (not a crash: worth a look).
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use obscura::scene::load::{Loaded, scene_from};
use obscura::{Algorithm, PrepareOptions, Scene, Viewport};

static SOFT: AtomicUsize = AtomicUsize::new(0);

/// Saves an input that did not crash but looks wrong (e.g. an accepted scene the
/// default camera cannot frame), without stopping the fuzzer.
pub fn soft_finding(target: &str, kind: &str, input: &[u8], detail: &str) {
    if SOFT.fetch_add(1, Ordering::Relaxed) > 200 {
        return;
    }
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in input {
        h = (h ^ u64::from(b)).wrapping_mul(0x100000001b3);
    }
    let dir = findings_dir();
    let _ = std::fs::create_dir_all(dir);
    let base = dir.join(format!("{target}-{kind}-{h:016x}"));
    let _ = std::fs::write(base.with_extension("bin"), input);
    let _ = std::fs::write(base.with_extension("txt"), detail);
}

/// `findings/soft` under the folder the fuzzer started in (fixed on the first call, so
/// a target that changes its working folder calls this first).
pub fn findings_dir() -> &'static Path {
    static DIR: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        std::env::current_dir()
            .unwrap_or_else(|_| PathBuf::from("."))
            .join("findings/soft")
    })
}

/// A private empty directory per process (for loaders that resolve side files).
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("obscura-fuzz-{tag}-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&d);
    d
}

/// Checks what a loader returned, then builds a scene and renders it.
pub fn check_loaded(target: &str, input: &[u8], loaded: Loaded) {
    for o in &loaded.objects {
        assert!(
            o.mesh.positions().iter().all(|p| p.is_finite()),
            "loader returned a non-finite position in object {:?}",
            o.name
        );
        assert!(
            o.transform.is_finite(),
            "loader returned a non-finite transform"
        );
    }
    let scene = match scene_from(loaded, "fuzz") {
        Ok(s) => s,
        Err(obscura::Error::EmptyScene(_)) => return,
        Err(e) => {
            soft_finding(target, "scene_from", input, &e.to_string());
            return;
        }
    };
    check_scene(target, input, &scene);
}

/// Frames a scene with its default camera and renders it with the z-buffer.
pub fn check_scene(target: &str, input: &[u8], scene: &Scene) {
    if scene.ensure_not_empty("fuzz").is_err() {
        return;
    }
    let viewport = Viewport::new(64, 48).expect("viewport");
    let camera = scene.default_camera(viewport.aspect());
    if let Err(e) = camera.validate() {
        soft_finding(
            target,
            "camera",
            input,
            &format!("{e}\nbounds {:?}", scene.bounds()),
        );
        return;
    }
    let view = match obscura::prepare(scene, &camera, viewport, &PrepareOptions::default()) {
        Ok(v) => v,
        Err(e) => {
            soft_finding(target, "prepare", input, &e.to_string());
            return;
        }
    };
    if let Err(e) = obscura::render(Algorithm::ZBuffer, &view, &Default::default()) {
        soft_finding(target, "render", input, &e.to_string());
    }
}

/// A triangle's three positions (f32, little-endian) and its indices (u16, padded to
/// four bytes): the binary buffer of the reference glTF and GLB.
const TRI_BIN: [u8; 44] = [
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x80, 0x3f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0x80, 0x3f, 0, 0, 0, 0, 0, 0, 1, 0, 2, 0, 0, 0,
];

/// The glTF JSON of the reference triangle; `uri` is the buffer's URI, or `None` for
/// a GLB's own binary chunk.
fn tri_gltf_json(uri: Option<&str>) -> String {
    let uri = uri.map_or(String::new(), |u| format!(", \"uri\": \"{u}\""));
    format!(
        "{{\"asset\": {{\"version\": \"2.0\"}}, \"scene\": 0, \"scenes\": [{{\"nodes\": [0]}}], \
         \"nodes\": [{{\"name\": \"root\", \"children\": [1], \"translation\": [1, 0, 0]}}, \
         {{\"mesh\": 0, \"scale\": [2, 2, 2]}}], \
         \"meshes\": [{{\"name\": \"tri\", \"primitives\": [{{\"attributes\": {{\"POSITION\": 0}}, \
         \"indices\": 1, \"material\": 0}}]}}], \
         \"materials\": [{{\"pbrMetallicRoughness\": {{\"baseColorFactor\": [1, 0.5, 0.2, 1]}}}}], \
         \"accessors\": [{{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \
         \"min\": [0, 0, 0], \"max\": [1, 1, 0]}}, \
         {{\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}}], \
         \"bufferViews\": [{{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}}, \
         {{\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}}], \
         \"buffers\": [{{\"byteLength\": 44{uri}}}]}}"
    )
}

/// The reference triangle as a GLB (header, JSON chunk, BIN chunk).
fn tri_glb() -> Vec<u8> {
    let mut json = tri_gltf_json(None).into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + TRI_BIN.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(TRI_BIN.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&TRI_BIN);
    out
}

/// A binary STL of one triangle.
fn tri_binary_stl() -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend_from_slice(&1u32.to_le_bytes());
    let floats: [f32; 12] = [0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0.];
    for f in floats {
        out.extend_from_slice(&f.to_le_bytes());
    }
    out.extend_from_slice(&[0, 0]);
    out
}

/// Writes the fixed mesh files a fuzzed scene file may reference into `dir`:
/// `tri.obj` (two objects, `mtllib tri.mtl`), `tri.mtl`, `tri.stl` (ASCII),
/// `bin.stl` (binary), `tri.gltf` with `tri.bin`, `tri.glb`, `tri.ply`, `empty.obj`
/// (white space only), `sub/quad.obj` and the link `sub/link.obj` to `../tri.obj`.
pub fn write_reference_meshes(dir: &Path) {
    let sub = dir.join("sub");
    let _ = std::fs::create_dir_all(&sub);
    let files: [(&str, Vec<u8>); 10] = [
        (
            "tri.obj",
            b"mtllib tri.mtl\no a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n\
              o b\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nusemtl blue\nf 4 5 6 7\n"
                .to_vec(),
        ),
        (
            "tri.mtl",
            b"newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n".to_vec(),
        ),
        (
            "tri.stl",
            b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
              vertex 0 1 0\nendloop\nendfacet\nendsolid t\n"
                .to_vec(),
        ),
        ("bin.stl", tri_binary_stl()),
        ("tri.gltf", tri_gltf_json(Some("tri.bin")).into_bytes()),
        ("tri.bin", TRI_BIN.to_vec()),
        ("tri.glb", tri_glb()),
        (
            "tri.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
              property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
              end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
                .to_vec(),
        ),
        ("empty.obj", b"\n  \n".to_vec()),
        (
            "sub/quad.obj",
            b"v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4\n".to_vec(),
        ),
    ];
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).expect("writing a reference mesh");
    }
    let link = sub.join("link.obj");
    let _ = std::fs::remove_file(&link);
    #[cfg(unix)]
    let _ = std::os::unix::fs::symlink("../tri.obj", &link);
}
