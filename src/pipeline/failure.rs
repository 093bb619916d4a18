//! How a command fails: bad input (exit code 2 on the command line) or a computation that
//! failed (exit code 1), with the message the user sees. The command line and the Python
//! package report the same [`Failure`]s, so a mistake reads the same in both.

/// Exit code for bad input (arguments, files, scenes).
pub const EXIT_BAD_INPUT: i32 = 2;
/// Exit code for a computation that failed.
pub const EXIT_FAILED: i32 = 1;

/// A failed command: what went wrong and which exit code it earns.
#[derive(Debug)]
pub enum Failure {
    /// The input is wrong; the message says how to fix it (exit code 2).
    Input(anyhow::Error),
    /// The computation failed (exit code 1).
    Compute(anyhow::Error),
}

impl Failure {
    /// Process exit code.
    pub fn exit_code(&self) -> i32 {
        match self {
            Failure::Input(_) => EXIT_BAD_INPUT,
            Failure::Compute(_) => EXIT_FAILED,
        }
    }
    /// The message shown to the user: each cause once (a message that already quotes its
    /// cause, as `cannot write X: <os error>. Check...` does, does not repeat it).
    pub fn message(&self) -> String {
        let (Failure::Input(e) | Failure::Compute(e)) = self;
        let mut text = String::new();
        for cause in e.chain() {
            let part = cause.to_string();
            if text.is_empty() {
                text = part;
            } else if !text.contains(&part) {
                text = format!("{text}: {part}");
            }
        }
        text
    }
}

/// Tag an error as bad input.
pub fn input<E: Into<anyhow::Error>>(e: E) -> Failure {
    Failure::Input(e.into())
}

/// Tag an error as a failed computation.
pub fn compute<E: Into<anyhow::Error>>(e: E) -> Failure {
    Failure::Compute(e.into())
}

/// A file that could not be written: bad input when the user's output path is at fault.
pub fn write_failure(e: crate::io::ExportError) -> Failure {
    if e.is_bad_input() {
        input(e)
    } else {
        compute(e)
    }
}
