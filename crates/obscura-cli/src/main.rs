//! `obscura`: render, compare and benchmark visibility algorithms from the command line.

mod allocator;
mod bench;
mod common;
mod compare;
mod grid;
mod lines;
mod out;
mod outputs;
mod render;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::out::errln;

/// Large buffers (the loaded scene, the prepared view, the frame) in whole huge pages:
/// a one-shot run otherwise spends milliseconds on page faults at their ends.
#[global_allocator]
static ALLOCATOR: allocator::HugePageAllocator = allocator::HugePageAllocator::new();

/// What can be seen? Clipping, culling and hidden-surface removal, every classical
/// algorithm behind one interface.
#[derive(Parser, Debug)]
#[command(name = "obscura", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
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
}

fn main() -> ExitCode {
    common::mark_start();
    let cli = Cli::parse();
    outputs::remove_temporaries_on_signal();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Lines(args) => lines::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("error: {}", common::message(&common::cli_error(e)));
            ExitCode::FAILURE
        }
    }
}
