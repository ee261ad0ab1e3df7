//! `obscura`: render, compare and benchmark visibility algorithms from the command line.

mod allocator;
mod bench;
mod cli;
mod common;
mod compare;
mod cull;
mod export;
mod grid;
mod lines;
mod out;
mod outputs;
mod render;

use std::process::ExitCode;

use clap::Parser;

use crate::cli::{Cli, Command};
use crate::out::errln;

/// Large buffers (the loaded scene, the prepared view, the frame) in whole huge pages:
/// a one-shot run otherwise spends milliseconds on page faults at their ends.
#[global_allocator]
static ALLOCATOR: allocator::HugePageAllocator = allocator::HugePageAllocator::new();

fn main() -> ExitCode {
    common::mark_start();
    let cli = Cli::parse();
    outputs::remove_temporaries_on_signal();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Lines(args) => lines::run(&args),
        Command::Cull(args) => cull::run(&args),
        Command::Export(args) => export::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            errln!("error: {}", common::message(&common::cli_error(e)));
            ExitCode::FAILURE
        }
    }
}
