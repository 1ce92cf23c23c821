//! The record of a run in its output directory (issue 16), as analysts keep one: which
//! alfe (version and commit), the command line, the rank count, the date and host, and
//! the deck as read with the defaults it resolved to (`deck.toml`); `summary.json`
//! carries the same under `run`.

use serde::Serialize;
use std::path::Path;

/// Who ran what, where and when.
#[derive(Debug, Clone, Serialize)]
pub struct RunRecord {
    pub version: String,
    pub commit: String,
    /// The command line as typed (arguments shell-quoted where needed).
    pub command: String,
    pub ranks: usize,
    /// Start of the run, ISO 8601 UTC.
    pub started: String,
    pub host: String,
    /// The working directory (deck paths and `--out` are relative to it).
    pub cwd: String,
    /// The built-in scene's name or the deck's path.
    pub deck: String,
}

impl RunRecord {
    /// The record of this process's run of `deck` on `ranks` ranks, started now.
    pub fn now(deck: &str, ranks: usize) -> Self {
        let secs = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        Self {
            version: env!("CARGO_PKG_VERSION").into(),
            commit: crate::COMMIT.into(),
            command: std::env::args()
                .map(|a| shell_quote(&a))
                .collect::<Vec<_>>()
                .join(" "),
            ranks,
            started: utc_iso8601(secs),
            host: super::lock::host(),
            cwd: std::env::current_dir()
                .map(|d| d.display().to_string())
                .unwrap_or_default(),
            deck: deck.into(),
        }
    }

    /// `deck.toml`: this record as a comment header, then the deck as read (defaults
    /// filled in) and what was resolved at run time (`resolved`, as comments).
    pub fn write_deck(&self, dir: &Path, echo: &str, resolved: &[String]) -> std::io::Result<()> {
        let mut s = format!(
            "# The deck of this run as alfe read it, with its defaults filled in.\n\
             # alfe {} (commit {}), {} rank(s), started {} on {}\n# command: {}\n# deck: {}\n",
            self.version, self.commit, self.ranks, self.started, self.host, self.command, self.deck
        );
        if !resolved.is_empty() {
            s.push_str("# resolved at run time:\n");
            for r in resolved {
                s.push_str(&format!("#   {r}\n"));
            }
        }
        s.push('\n');
        s.push_str(echo);
        std::fs::write(dir.join("deck.toml"), s)
    }
}

/// `a` as a shell word: unchanged if it needs no quoting, else single-quoted.
fn shell_quote(a: &str) -> String {
    let plain = !a.is_empty()
        && a.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c));
    if plain {
        a.into()
    } else {
        format!("'{}'", a.replace('\'', "'\\''"))
    }
}

/// Seconds since the Unix epoch as `YYYY-MM-DDTHH:MM:SSZ` (Howard Hinnant's
/// civil-from-days).
pub fn utc_iso8601(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        (rem / 60) % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_iso_utc() {
        assert_eq!(utc_iso8601(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_iso8601(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_iso8601(1_795_608_000 + 3_723), "2026-11-25T13:02:03Z");
        assert_eq!(utc_iso8601(4_107_542_399), "2100-02-28T23:59:59Z");
    }

    #[test]
    fn shell_words_are_quoted_only_when_needed() {
        assert_eq!(shell_quote("--out=dir/x"), "--out=dir/x");
        assert_eq!(shell_quote("my deck.toml"), "'my deck.toml'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
        assert_eq!(shell_quote(""), "''");
    }
}
