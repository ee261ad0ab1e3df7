//! The hidden-surface and structure tests that look inside the crate (SIMD kernels, BVH
//! packets and traversal, the random scene generators, the RNG): once integration tests
//! under `tests/`, which made those internals public only to be named. Each file is
//! the suite it was, assertion for assertion; `tests/` keeps what a user can do with
//! the public API.

mod bsp;
mod budget;
mod cells;
mod cross_validation;
mod cull;
mod cull_buffer;
mod cull_clusters;
mod depth_sort;
mod hsr_scenes;
mod occluder_meshes;
mod occluders;
mod octree;
mod portals;
mod prt_cells;
mod raycast;
mod scanline;
mod warnock;
