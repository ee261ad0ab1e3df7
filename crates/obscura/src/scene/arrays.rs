//! Scenes from meshes already in memory: vertex positions and faces as flat arrays, as
//! an engine, a simulation or NumPy holds them.
//!
//! The arrays go through [`MeshBuilder`] like every loaded file, so the same rules hold
//! (see [`MeshBuilder`]): an index out of range is an error naming the face; degenerate
//! and self-intersecting faces are dropped and counted, keeping their face ids;
//! non-planar and concave polygons are triangulated and counted. A non-finite
//! position, or one beyond [`super::MAX_COORDINATE`], is an error naming the vertex. Face
//! ids are the faces' positions in the arrays.

use super::{LoadReport, Mesh, MeshBuilder, ObjectDesc, Scene};
use crate::{Error, Result};

/// The faces of a mesh given as arrays of vertex indices (counter-clockwise seen from
/// the front, 0-based).
#[derive(Clone, Copy, Debug)]
pub enum Faces<'a> {
    /// One triangle per entry.
    Triangles(&'a [[u32; 3]]),
    /// Polygons of any size in compressed sparse rows: polygon `k` is
    /// `indices[offsets[k] as usize..offsets[k + 1] as usize]`. `offsets` starts at 0,
    /// never decreases and ends at `indices.len()` (one more entry than polygons).
    Polygons {
        /// Where each polygon starts in `indices`, and the end of the last.
        offsets: &'a [u32],
        /// The polygons' vertex indices, one after the other.
        indices: &'a [u32],
    },
}

impl Faces<'_> {
    /// How many faces there are (for [`Faces::Polygons`], `offsets.len() - 1`; an
    /// empty `offsets` counts as none).
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Faces::Triangles(t) => t.len(),
            Faces::Polygons { offsets, .. } => offsets.len().saturating_sub(1),
        }
    }

    /// Whether there is no face.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Mesh {
    /// A mesh from vertex positions and faces, checked and cleaned by the rules of
    /// [`MeshBuilder`] (the bad-face rules every loader follows); the report says what was
    /// dropped or triangulated. Errors name the vertex or the face:
    /// `face 7: vertex index 12 is out of range (...)`.
    pub fn from_arrays(positions: &[[f64; 3]], faces: Faces<'_>) -> Result<(Mesh, LoadReport)> {
        let invalid = |message: String| Error::InvalidObject {
            object: "arrays".into(),
            message,
        };
        let mut b = MeshBuilder::with_capacity(positions.len(), faces.len());
        for (i, p) in positions.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(invalid(format!("vertex {i} is not finite")));
            }
            if let Some(m) = super::load::coordinate_out_of_range(*p) {
                return Err(invalid(format!("vertex {i}: {m}")));
            }
            b.push_position(glam::DVec3::from_array(*p));
        }
        let mut push = |k: usize, face: &[u32]| {
            b.push_face(face, None)
                .map(|_| ())
                .map_err(|e| invalid(format!("face {k}: {e}")))
        };
        match faces {
            Faces::Triangles(triangles) => {
                for (k, t) in triangles.iter().enumerate() {
                    push(k, t)?;
                }
            }
            Faces::Polygons { offsets, indices } => {
                check_offsets(offsets, indices.len()).map_err(invalid)?;
                for (k, w) in offsets.windows(2).enumerate() {
                    push(k, &indices[w[0] as usize..w[1] as usize])?;
                }
            }
        }
        Ok(b.finish())
    }
}

/// An error message unless `offsets` are compressed-sparse-row offsets into `len`
/// indices: starting at 0, never decreasing, ending at `len`.
fn check_offsets(offsets: &[u32], len: usize) -> std::result::Result<(), String> {
    let (Some(&first), Some(&last)) = (offsets.first(), offsets.last()) else {
        return Err(
            "offsets is empty: it needs one more entry than there are faces, \
                    starting at 0"
                .into(),
        );
    };
    if first != 0 {
        return Err(format!("offsets[0] is {first}, not 0"));
    }
    if let Some(k) = offsets.windows(2).position(|w| w[1] < w[0]) {
        return Err(format!(
            "face {k}: offsets[{}] = {} is below offsets[{k}] = {} (offsets never decrease)",
            k + 1,
            offsets[k + 1],
            offsets[k]
        ));
    }
    if last as usize != len {
        return Err(format!(
            "the last offset is {last}, not the number of indices, {len}"
        ));
    }
    Ok(())
}

impl Scene {
    /// A scene of one object, named `arrays`, made from vertex positions and faces
    /// already in memory (see [`Mesh::from_arrays`] for the rules and the errors). Face
    /// ids are the faces' positions in `faces`. As for a loaded file, what was dropped
    /// or triangulated is in [`Scene::report`], and a mesh left without a usable face
    /// is [`Error::EmptyScene`].
    ///
    /// ```
    /// use obscura::scene::Faces;
    /// use obscura::{Camera, Scene, Viewport, prepare, PrepareOptions, render, Algorithm};
    /// use glam::DVec3;
    ///
    /// // A unit square in the z = 0 plane, as two triangles, facing +z.
    /// let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    /// let scene = Scene::from_arrays(&positions, Faces::Triangles(&[[0, 1, 2], [0, 2, 3]]))?;
    /// assert_eq!(scene.face_count(), 2);
    ///
    /// let viewport = Viewport::new(64, 64)?;
    /// let camera = Camera::perspective(
    ///     DVec3::new(0.5, 0.5, 3.0), DVec3::new(0.5, 0.5, 0.0), DVec3::Y, 45.0, 0.1, 10.0,
    /// );
    /// let view = prepare(&scene, &camera, viewport, &PrepareOptions::default())?;
    /// let (frame, _) = render(Algorithm::ZBuffer, &view, &Default::default())?;
    /// assert!(frame.id(32, 32) < 2);
    /// # Ok::<(), obscura::Error>(())
    /// ```
    pub fn from_arrays(positions: &[[f64; 3]], faces: Faces<'_>) -> Result<Scene> {
        let (mesh, report) = Mesh::from_arrays(positions, faces)?;
        let mut scene = Scene::new();
        scene.add(ObjectDesc::new("arrays", mesh))?;
        scene.report_mut().merge(&report);
        scene.ensure_not_empty("the arrays")?;
        Ok(scene)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_offsets_are_named() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let err = |offsets: &[u32], indices: &[u32]| {
            Scene::from_arrays(&p, Faces::Polygons { offsets, indices })
                .unwrap_err()
                .to_string()
        };
        assert!(err(&[], &[]).contains("offsets is empty"));
        assert!(err(&[1, 3], &[0, 1, 2]).contains("offsets[0] is 1"));
        let e = err(&[0, 3, 2, 3], &[0, 1, 2]);
        assert!(
            e.contains("face 1: offsets[2] = 2 is below offsets[1] = 3"),
            "{e}"
        );
        let e = err(&[0, 3], &[0, 1, 2, 0]);
        assert!(
            e.contains("last offset is 3, not the number of indices, 4"),
            "{e}"
        );
    }
}
