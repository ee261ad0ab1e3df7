//! `obscura`: render, compare and benchmark visibility algorithms from the command line.

mod common;
mod render;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
