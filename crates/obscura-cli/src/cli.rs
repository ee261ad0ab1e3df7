//! The command line's definition: its subcommands and their arguments (parsed by clap).
//! One definition for the binary (`main.rs`) and the `cli_args` fuzz target, which
//! compiles this file by path.

use clap::{Parser, Subcommand};

use crate::{bench, compare, cull, export, lines, render};

/// What can be seen? Clipping, culling and hidden-surface removal, every classical
/// algorithm behind one interface.
#[derive(Parser, Debug)]
#[command(name = "obscura", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to a PNG (and optionally face ids and depths as NumPy arrays).
    #[command(after_help = render::EXAMPLES)]
    Render(render::RenderArgs),
    /// Render with every algorithm (or a list), compare each to the z-buffer, and write a
    /// grid of pictures and difference masks.
    #[command(after_help = compare::EXAMPLES)]
    Compare(compare::CompareArgs),
    /// Time each algorithm over a sweep of face counts and fit the growth exponent.
    #[command(after_help = bench::EXAMPLES)]
    Bench(bench::BenchArgs),
    /// Draw the visible (and hidden) lines of a scene or a height field as SVG for
    /// people and pen plotters, with a PNG preview and the JSON of every edge.
    #[command(after_help = lines::EXAMPLES)]
    Lines(lines::LinesArgs),
    /// What each occlusion-culling method removes from a view or a camera walk, and
    /// why: objects, clusters and faces tested, culled and drawn, the time of each
    /// stage; the surviving face ids, and a picture of the decisions.
    #[command(after_help = cull::EXAMPLES)]
    Cull(cull::CullArgs),
    /// Write a scene (a file, a scene file or a demo) as OBJ with its faces in id order.
    #[command(after_help = export::EXAMPLES)]
    Export(export::ExportArgs),
}
