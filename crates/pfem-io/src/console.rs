//! Lines for the terminal that never panic.
//!
//! `println!` and `eprintln!` panic when their stream is a closed pipe
//! (`pfem check scene.toml | head -1`, a `tee` or log collector that went
//! away): a finished run then reported a failure, and a run whose stderr
//! was closed from the start exited with status 101 before writing
//! anything (session 52's review). What pfem prints is a report on a run
//! whose real outputs are its files, so a line nobody reads is dropped:
//! [`outln!`](crate::outln) and [`errln!`](crate::errln) take
//! `println!`'s arguments and ignore the write's error.

use std::fmt;
use std::io::Write;

/// Writes `args` and a newline to stdout; a failed write (a closed pipe)
/// is ignored. What [`outln!`](crate::outln) calls.
pub fn out(args: fmt::Arguments<'_>) {
    let mut s = std::io::stdout().lock();
    let _ = writeln!(s, "{args}");
}

/// Writes `args` and a newline to stderr; a failed write is ignored.
/// What [`errln!`](crate::errln) calls.
pub fn err(args: fmt::Arguments<'_>) {
    let mut s = std::io::stderr().lock();
    let _ = writeln!(s, "{args}");
}

/// Writes `args` to stdout without a newline and flushes; a failed write
/// is ignored.
pub fn out_part(args: fmt::Arguments<'_>) {
    let mut s = std::io::stdout().lock();
    let _ = write!(s, "{args}");
    let _ = s.flush();
}

/// `println!` that does not panic on a closed stdout (see [`crate::console`]).
///
/// ```
/// pfem_io::outln!("{} steps", 3);
/// ```
#[macro_export]
macro_rules! outln {
    () => {
        $crate::console::out(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::console::out(format_args!($($arg)*))
    };
}

/// `eprintln!` that does not panic on a closed stderr (see [`crate::console`]).
///
/// ```
/// pfem_io::errln!("warning: {}", "a note");
/// ```
#[macro_export]
macro_rules! errln {
    () => {
        $crate::console::err(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::console::err(format_args!($($arg)*))
    };
}
