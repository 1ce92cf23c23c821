//! The tokenizer: ASCII tokens with their lines, and raw binary fields with their byte
//! offsets.

use std::fmt;

/// Where something is in a file, for messages: a line of an ASCII file, or a byte offset
/// (from 0) in a binary one, where lines mean nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Loc {
    Line(usize),
    Byte(usize),
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Loc::Line(n) => write!(f, "line {n}"),
            Loc::Byte(n) => write!(f, "byte {n}"),
        }
    }
}

impl Loc {
    /// The line for [`Surface::quad_lines`]: 0 (unknown, as `mesh::sheet` takes it) in a
    /// binary file, whose facets are named by element tag alone.
    pub(super) fn line(self) -> usize {
        match self {
            Loc::Line(n) => n,
            Loc::Byte(_) => 0,
        }
    }
}

/// What a token that is not UTF-8 text (raw bytes where a keyword or a number was
/// expected) is shown as in messages.
pub(super) const NOT_TEXT: &str = "(binary data)";

/// Whitespace-separated tokens with line numbers; a double-quoted string is one token.
/// Lazy, so a file is refused at its header before its bytes are looked at. In a binary
/// file it also reads the raw fields between the ASCII lines.
pub(super) struct Lexer<'a> {
    pub(super) b: &'a [u8],
    pub(super) pos: usize,
    pub(super) line: usize,
    /// The section being read, for end-of-file messages.
    pub(super) section: &'a str,
    /// A binary file, from its `$MeshFormat` line on: places are then byte offsets.
    pub(super) binary: bool,
    /// The byte order of a binary file's raw fields.
    pub(super) big_endian: bool,
    /// Bytes in a binary size_t: the data size of MSH 4.1 (8; 4 from a 32-bit Gmsh).
    pub(super) size_t: usize,
}

impl<'a> Lexer<'a> {
    pub(super) fn next(&mut self) -> Option<(&'a str, Loc)> {
        let b = self.b;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            if b[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        if self.pos >= b.len() {
            return None;
        }
        let start = self.pos;
        let at = self.here();
        if b[start] == b'"' {
            self.pos += 1;
            while self.pos < b.len() && b[self.pos] != b'"' && b[self.pos] != b'\n' {
                self.pos += 1;
            }
            if self.pos < b.len() && b[self.pos] == b'"' {
                self.pos += 1;
            }
        } else {
            while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
        }
        Some((
            std::str::from_utf8(&b[start..self.pos]).unwrap_or(NOT_TEXT),
            at,
        ))
    }

    /// The current place: its line in an ASCII file, its byte offset in a binary one.
    pub(super) fn here(&self) -> Loc {
        if self.binary {
            Loc::Byte(self.pos)
        } else {
            Loc::Line(self.line)
        }
    }

    pub(super) fn tok(&mut self, what: &str) -> Result<(&'a str, Loc), String> {
        self.next()
            .ok_or_else(|| format!("end of file inside ${}: expected {what}", self.section))
    }

    pub(super) fn uint(&mut self, what: &str) -> Result<u64, String> {
        let (t, at) = self.tok(what)?;
        t.parse()
            .map_err(|_| format!("{at}: expected {what} (a non-negative integer), found \"{t}\""))
    }

    pub(super) fn count(&mut self, what: &str) -> Result<usize, String> {
        let (t, at) = self.tok(what)?;
        let n: usize = t.parse().map_err(|_| {
            format!("{at}: expected {what} (a non-negative integer), found \"{t}\"")
        })?;
        // Guards allocations against garbage counts: nothing in a file is bigger than it.
        if n > self.b.len() {
            return Err(format!(
                "{at}: {what} {n} is larger than the file could hold"
            ));
        }
        Ok(n)
    }

    pub(super) fn int(&mut self, what: &str) -> Result<i64, String> {
        let (t, at) = self.tok(what)?;
        t.parse()
            .map_err(|_| format!("{at}: expected {what} (an integer), found \"{t}\""))
    }

    pub(super) fn real(&mut self, what: &str) -> Result<f64, String> {
        let (t, at) = self.tok(what)?;
        match t.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(format!(
                "{at}: expected {what} (a finite number), found \"{t}\""
            )),
        }
    }

    pub(super) fn skip(&mut self, n: usize, what: &str) -> Result<(), String> {
        for _ in 0..n {
            self.tok(what)?;
        }
        Ok(())
    }

    /// The closing `$End<section>` line.
    pub(super) fn end(&mut self) -> Result<(), String> {
        let want = format!("$End{}", self.section);
        match self.next() {
            Some((t, _)) if t == want => Ok(()),
            Some((t, at)) => Err(format!("{at}: expected {want}, found \"{t}\"")),
            None => Err(format!("end of file: expected {want}")),
        }
    }

    /// The end of the ASCII line before binary data, which starts right after its '\n'
    /// (as Gmsh reads it): no more whitespace may be skipped, for a count's first byte can
    /// be a space or a newline.
    pub(super) fn line_end(&mut self) -> Result<(), String> {
        let b = self.b;
        while self.pos < b.len() && matches!(b[self.pos], b' ' | b'\t' | b'\r') {
            self.pos += 1;
        }
        if self.pos < b.len() && b[self.pos] == b'\n' {
            self.pos += 1;
            self.line += 1;
            return Ok(());
        }
        Err(format!(
            "byte {}: expected the end of the line before the binary data of ${}",
            self.pos, self.section
        ))
    }

    /// The next `n` raw bytes of a binary block.
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let left = self.b.len() - self.pos;
        if left < n {
            return Err(format!(
                "byte {}: end of file inside ${}: expected {what} ({n} bytes, {left} left)",
                self.pos, self.section
            ));
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// A binary unsigned integer of `width` bytes (at most 8) in the file's byte order.
    pub(super) fn b_uint(&mut self, width: usize, what: &str) -> Result<u64, String> {
        let s = self.take(width, what)?;
        let fold = |v: u64, &x: &u8| v << 8 | u64::from(x);
        Ok(if self.big_endian {
            s.iter().fold(0, fold)
        } else {
            s.iter().rev().fold(0, fold)
        })
    }

    /// A binary C int (4 bytes, signed).
    pub(super) fn b_int(&mut self, what: &str) -> Result<i64, String> {
        Ok(i64::from(self.b_uint(4, what)? as u32 as i32))
    }

    /// A binary size_t: MSH 4.1's counts and node and element tags.
    pub(super) fn b_size(&mut self, what: &str) -> Result<u64, String> {
        self.b_uint(self.size_t, what)
    }

    /// A binary size_t count of items of at least `item` bytes each, refused when the
    /// rest of the file could not hold them: a garbled count never drives a huge
    /// allocation or a long loop.
    pub(super) fn b_count(&mut self, what: &str, item: usize) -> Result<usize, String> {
        let at = Loc::Byte(self.pos);
        let n = self.b_size(what)?;
        self.room(n, item, what, at)
    }

    /// `n` (read at `at`) as a count of items of at least `item` bytes that the
    /// rest of the file can hold.
    pub(super) fn room(&self, n: u64, item: usize, what: &str, at: Loc) -> Result<usize, String> {
        let left = self.b.len() - self.pos;
        match usize::try_from(n) {
            Ok(k) if k <= left / item.max(1) => Ok(k),
            _ => Err(format!(
                "{at}: {what} {n} is more than the {left} bytes left in the file could hold (a cut-short or garbled file)"
            )),
        }
    }

    /// A binary double, which must be finite.
    pub(super) fn b_real(&mut self, what: &str) -> Result<f64, String> {
        let at = self.pos;
        let x = f64::from_bits(self.b_uint(8, what)?);
        if x.is_finite() {
            Ok(x)
        } else {
            Err(format!(
                "byte {at}: expected {what} (a finite number), found {x}"
            ))
        }
    }
}
