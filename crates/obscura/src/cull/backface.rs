//! Back-face culling.
//!
//! Source: seed 000 ("Περικοπή Πίσω Όψεων") and seed 002 ("Back face culling"): a face
//! of a closed, opaque, 2-manifold solid whose outward normal `n` points away from the
//! viewer (`n · v < 0`, `v` towards the eye) cannot be seen. It removes about half the
//! faces for O(1) each. Convexity is not required.
//!
//! Faces exactly edge-on (`n · v = 0`) are culled too: they cover no area.

use glam::DVec3;

/// Which objects have their back faces culled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BackfaceMode {
    /// Only objects flagged closed (the seeds' condition): the default.
    #[default]
    Closed,
    /// Every object, closed or not (what an engine does when it trusts its content).
    All,
    /// None.
    Off,
}

impl BackfaceMode {
    /// Whether faces of an object with this closed flag are culled.
    #[must_use]
    pub fn applies_to(self, closed: bool) -> bool {
        match self {
            BackfaceMode::Closed => closed,
            BackfaceMode::All => true,
            BackfaceMode::Off => false,
        }
    }
}

/// Whether a face with (unnormalized, outward) normal `normal` through `point` is seen
/// from behind by a perspective eye at `eye`: `normal · (eye - point) <= 0`.
#[inline]
#[must_use]
pub fn is_back_facing_perspective(normal: DVec3, point: DVec3, eye: DVec3) -> bool {
    normal.dot(eye - point) <= 0.0
}

/// Whether a face is seen from behind by a parallel projection looking along `view_dir`.
#[inline]
#[must_use]
pub fn is_back_facing_parallel(normal: DVec3, view_dir: DVec3) -> bool {
    normal.dot(-view_dir) <= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facing() {
        let n = DVec3::Z;
        assert!(!is_back_facing_perspective(
            n,
            DVec3::ZERO,
            DVec3::new(0., 0., 5.)
        ));
        assert!(is_back_facing_perspective(
            n,
            DVec3::ZERO,
            DVec3::new(0., 0., -5.)
        ));
        assert!(is_back_facing_perspective(
            n,
            DVec3::ZERO,
            DVec3::new(5., 0., 0.)
        )); // edge-on
        assert!(!is_back_facing_parallel(n, -DVec3::Z));
        assert!(is_back_facing_parallel(n, DVec3::Z));
        assert!(BackfaceMode::Closed.applies_to(true) && !BackfaceMode::Closed.applies_to(false));
    }
}
