//! Feature edges of a mesh, after welding: silhouettes, creases, boundaries, borders and
//! intersection lines (placeholder: every welded edge, kind `Other`, until the feature
//! rules land).

use super::{DrawnEdge, EdgeKind, EdgeKinds};
use crate::{Result, SceneIndex, View};

/// Which edges to find.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct EdgeOptions {
    /// The kinds to keep.
    pub kinds: EdgeKinds,
    /// Dihedral angle in degrees above which an edge is a crease.
    pub crease_degrees: f64,
}

impl Default for EdgeOptions {
    fn default() -> Self {
        EdgeOptions {
            kinds: EdgeKinds::default(),
            crease_degrees: 30.0,
        }
    }
}

/// The edges of the objects `view` keeps, in world space.
pub fn feature_edges(
    index: &SceneIndex,
    view: &View,
    _options: &EdgeOptions,
) -> Result<Vec<DrawnEdge>> {
    let scene = index.scene();
    let mut out = Vec::new();
    let mut vertex_base = 0u32;
    for (k, (object, adjacency)) in scene
        .objects()
        .iter()
        .zip(index.edge_adjacency())
        .enumerate()
    {
        if view.kept_objects()[k] {
            let p = object.mesh.positions();
            for e in &adjacency.edges {
                out.push(DrawnEdge {
                    vertices: Some([vertex_base + e.a, vertex_base + e.b]),
                    object: Some(k as u32),
                    kind: EdgeKind::Other,
                    faces: [
                        e.forward.map(|f| view.polygon_base()[k] + f),
                        e.backward.map(|f| view.polygon_base()[k] + f),
                    ],
                    world: [
                        object.transform.transform_point3(p[e.a as usize]),
                        object.transform.transform_point3(p[e.b as usize]),
                    ],
                });
            }
        }
        vertex_base += object.mesh.positions().len() as u32;
    }
    Ok(out)
}
