//! SVG output of a [`super::Drawing`] (placeholder).
