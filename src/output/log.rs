//! The run's log: what rank 0 prints (progress lines, warnings, the final line or the
//! error) also goes to `<out>/log.txt`, so a run started in the background or on a
//! cluster leaves its story beside its results. Other ranks log nothing.

use std::fs::File;
use std::io::Write;
use std::path::Path;

pub struct Log {
    file: Option<File>,
    /// Print to stdout as well (rank 0 without `--quiet`).
    echo: bool,
}

impl Log {
    /// Rank 0's log in `dir` (printing unless `quiet`); `None` on other ranks. A log that
    /// cannot be created only prints: the results themselves report a failing disk.
    pub fn open(dir: &Path, is_root: bool, quiet: bool) -> Self {
        if !is_root {
            return Self {
                file: None,
                echo: false,
            };
        }
        Self {
            file: File::create(dir.join("log.txt")).ok(),
            echo: !quiet,
        }
    }

    /// A log that neither prints nor writes.
    pub fn silent() -> Self {
        Self {
            file: None,
            echo: false,
        }
    }

    /// A line on stdout (unless quiet) and in the log.
    pub fn line(&mut self, s: &str) {
        if self.echo {
            println!("{s}");
        }
        self.file_only(s);
    }

    /// A line in the log alone (what the caller prints itself, or what `--quiet` hides).
    pub fn file_only(&mut self, s: &str) {
        if let Some(f) = &mut self.file {
            if writeln!(f, "{s}").and_then(|_| f.flush()).is_err() {
                self.file = None;
            }
        }
    }
}
