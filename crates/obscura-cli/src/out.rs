//! Printing the report without panicking when nobody reads it any more.
//!
//! Rust ignores SIGPIPE, so a write to a closed pipe (`obscura compare | head -1`) returns
//! `BrokenPipe`, on which `println!` panics. The report goes through [`outln!`] and
//! [`out!`] instead: a closed standard output ends the program quietly with status 0, as
//! most Unix tools do when their reader has gone; any other write error ends it with an
//! error message and status 1. Either way, output files not yet complete are discarded. Messages to standard error go through [`errln!`], which
//! drops them if standard error itself is closed (there is nobody left to tell).

use std::io::Write;

/// Writes formatted text to standard output; see the module docs for write errors.
pub fn stdout(args: std::fmt::Arguments<'_>) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args) {
        failed(&e);
    }
}

/// Writes formatted text to standard error, ignoring errors.
pub fn stderr(args: std::fmt::Arguments<'_>) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// Ends the program after standard output failed.
fn failed(e: &std::io::Error) -> ! {
    crate::outputs::discard_pending();
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    stderr(format_args!("error: writing to standard output: {e}\n"));
    std::process::exit(1);
}

/// `print!` that ends the program quietly on a closed standard output.
macro_rules! out {
    ($($arg:tt)*) => { $crate::out::stdout(format_args!($($arg)*)) };
}

/// `println!` that ends the program quietly on a closed standard output.
macro_rules! outln {
    () => { $crate::out::stdout(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::out::stdout(format_args!("{}\n", format_args!($($arg)*))) };
}

/// `eprintln!` that ignores a closed standard error.
macro_rules! errln {
    ($($arg:tt)*) => { $crate::out::stderr(format_args!("{}\n", format_args!($($arg)*))) };
}

pub(crate) use {errln, out, outln};
