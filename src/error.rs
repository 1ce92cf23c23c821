//! One error type for the whole program, with the exit code each kind maps to.
//!
//! Exit codes are part of the CLI contract (README): 0 success, 2 bad input (deck,
//! mesh, command line, partition file), 3 the solution did not converge (everything
//! converged so far is written), 1 any other runtime failure (I/O, MPI).

use std::fmt;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The user's input is wrong: deck, mesh file, command line, partition cache.
    Input,
    /// A load step could not be converged within the solver's budget.
    Convergence,
    /// Anything else: file system, HDF5, MPI.
    Runtime,
    /// Ended by SIGINT or SIGTERM after a converged step (the run's summary written): exit
    /// status 128 + the signal's number.
    Interrupted(i32),
}

#[derive(Debug, Clone)]
pub struct Error {
    pub kind: ErrorKind,
    pub message: String,
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn input(message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::Input,
            message: message.into(),
        }
    }
    pub fn convergence(message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::Convergence,
            message: message.into(),
        }
    }
    /// A run ended by signal `sig`; `message` is its summary's headline.
    pub fn interrupted(sig: i32, message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::Interrupted(sig),
            message: message.into(),
        }
    }
    pub fn runtime(message: impl Into<String>) -> Self {
        Self {
            kind: ErrorKind::Runtime,
            message: message.into(),
        }
    }
    pub fn exit_code(&self) -> i32 {
        match self.kind {
            ErrorKind::Input => 2,
            ErrorKind::Convergence => 3,
            ErrorKind::Runtime => 1,
            ErrorKind::Interrupted(sig) => 128 + sig,
        }
    }
    /// Prefix the message with context ("deck foo.toml: ...").
    pub fn context(mut self, ctx: impl fmt::Display) -> Self {
        self.message = format!("{ctx}: {}", self.message);
        self
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Error::runtime(e.to_string())
    }
}
