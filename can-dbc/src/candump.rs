//! can-utils log files: `(1700000000.123456) vcan0 123#DEADBEEF`, one frame per line.
//!
//! Supported: 3-hex-digit standard ids, 8-hex-digit extended ids, data of 0..=8 bytes, remote
//! frames `#R` with an optional DLC digit (`123#R4`). CAN FD lines (`123##1...`) and classic
//! frames with a DLC beyond 8 (`..._9`) are refused with a clear error: the hand bus is
//! classic CAN. Every malformed line is reported with its line number and what is wrong;
//! parsing never panics. A line is read into a buffer of at most [`MAX_LINE_BYTES`]: a file
//! without newlines is refused at its first line, never buffered whole.

use std::fmt::Write as _;
use std::io::{self, BufRead, Read, Write};
use std::path::Path;

use embedded_can::{ExtendedId, StandardId};

use crate::CanFrame;

/// Longest line accepted, bytes (without its newline). The longest valid line, a 20-digit
/// timestamp, a 15-character interface and an extended frame of 8 bytes, is under 70 bytes.
pub const MAX_LINE_BYTES: usize = 256;

/// One log line: receive time, interface and frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LogEntry {
    /// Receive time in µs since the Unix epoch (or any epoch the recorder used).
    pub time_us: u64,
    /// Interface name, e.g. `vcan0`.
    pub iface: String,
    /// The frame.
    pub frame: CanFrame,
}

/// What is wrong with one line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LineError {
    /// No `(sec.usec)` at the start.
    #[error("expected a timestamp \"(seconds.microseconds)\" at the start of the line")]
    MissingTimestamp,
    /// The timestamp is not `digits.6digits`.
    #[error("bad timestamp {0:?}: expected seconds, a dot and exactly 6 digits of microseconds")]
    BadTimestamp(String),
    /// No interface name after the timestamp.
    #[error("missing interface name after the timestamp")]
    MissingInterface,
    /// No frame after the interface.
    #[error("missing frame (ID#DATA) after the interface name")]
    MissingFrame,
    /// More fields than timestamp, interface and frame.
    #[error("unexpected text after the frame: {0:?}")]
    TrailingText(String),
    /// No `#` in the frame field.
    #[error("frame {0:?} has no '#' between id and data")]
    MissingHash(String),
    /// A CAN FD line.
    #[error("CAN FD frame (\"##\") is not supported: the hand bus is classic CAN")]
    CanFd,
    /// The id is not 3 or 8 hex digits.
    #[error("bad id {0:?}: expected 3 hex digits (11-bit) or 8 hex digits (29-bit)")]
    BadId(String),
    /// The id does not fit its width.
    #[error("id {id:#x} exceeds the {bits}-bit range")]
    IdOutOfRange {
        /// The id.
        id: u32,
        /// 11 or 29.
        bits: u8,
    },
    /// Data with a non-hex character or an odd number of digits.
    #[error("bad data {0:?}: expected pairs of hex digits")]
    BadData(String),
    /// More than 8 data bytes, or a DLC beyond 8.
    #[error("{0} data bytes: classic CAN carries at most 8")]
    TooLong(usize),
    /// A remote frame with a bad DLC digit.
    #[error("bad remote frame DLC {0:?}: expected one digit 0..8 after 'R'")]
    BadRemoteDlc(String),
    /// The line is longer than [`MAX_LINE_BYTES`].
    #[error("line longer than {MAX_LINE_BYTES} bytes: not a candump line")]
    LineTooLong,
    /// The line is not UTF-8 text.
    #[error("byte {0} is not UTF-8 text")]
    NotUtf8(usize),
}

/// Reading a log failed.
#[derive(Debug, thiserror::Error)]
pub enum CandumpError {
    /// The file or stream failed.
    #[error("reading the log failed: {0}")]
    Io(#[from] io::Error),
    /// A malformed line.
    #[error("line {line}: {error}")]
    Line {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        error: LineError,
    },
}

fn parse_timestamp(field: &str) -> Result<u64, LineError> {
    let bad = || LineError::BadTimestamp(field.to_string());
    let inner = field
        .strip_prefix('(')
        .and_then(|f| f.strip_suffix(')'))
        .ok_or(LineError::MissingTimestamp)?;
    let (secs, usecs) = inner.split_once('.').ok_or_else(bad)?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(secs) || usecs.len() != 6 || !digits(usecs) {
        return Err(bad());
    }
    let secs: u64 = secs.parse().map_err(|_| bad())?;
    let usecs: u64 = usecs.parse().map_err(|_| bad())?;
    secs.checked_mul(1_000_000)
        .and_then(|t| t.checked_add(usecs))
        .ok_or_else(bad)
}

fn hex_byte(pair: &[u8]) -> Option<u8> {
    let digit = |b: u8| (b as char).to_digit(16);
    Some((digit(pair[0])? * 16 + digit(pair[1])?) as u8)
}

/// Parses the `ID#DATA` field.
pub fn parse_frame(field: &str) -> Result<CanFrame, LineError> {
    let (id_text, rest) = field
        .split_once('#')
        .ok_or_else(|| LineError::MissingHash(field.to_string()))?;
    if rest.starts_with('#') {
        return Err(LineError::CanFd);
    }
    let is_hex = |s: &str| s.bytes().all(|b| b.is_ascii_hexdigit());
    if !is_hex(id_text) || !(id_text.len() == 3 || id_text.len() == 8) {
        return Err(LineError::BadId(id_text.to_string()));
    }
    let id = u32::from_str_radix(id_text, 16).map_err(|_| LineError::BadId(id_text.into()))?;
    let id: embedded_can::Id = if id_text.len() == 3 {
        let std = u16::try_from(id).ok().and_then(StandardId::new);
        std.ok_or(LineError::IdOutOfRange { id, bits: 11 })?.into()
    } else {
        ExtendedId::new(id)
            .ok_or(LineError::IdOutOfRange { id, bits: 29 })?
            .into()
    };
    if let Some(dlc) = rest.strip_prefix(['R', 'r']) {
        let dlc = match dlc {
            "" => 0,
            d if d.len() == 1 && d.as_bytes()[0].is_ascii_digit() => {
                usize::from(d.as_bytes()[0] - b'0')
            }
            d => return Err(LineError::BadRemoteDlc(d.to_string())),
        };
        if dlc > 8 {
            return Err(LineError::BadRemoteDlc(rest[1..].to_string()));
        }
        return CanFrame::new_remote(id, dlc).ok_or(LineError::TooLong(dlc));
    }
    if let Some((_, dlc)) = rest.split_once('_') {
        return Err(LineError::TooLong(dlc.parse().unwrap_or(9)));
    }
    if rest.len() % 2 != 0 || !is_hex(rest) {
        return Err(LineError::BadData(rest.to_string()));
    }
    if rest.len() > 16 {
        return Err(LineError::TooLong(rest.len() / 2));
    }
    let mut data = [0u8; 8];
    let mut n = 0;
    for pair in rest.as_bytes().chunks(2) {
        data[n] = hex_byte(pair).ok_or_else(|| LineError::BadData(rest.to_string()))?;
        n += 1;
    }
    CanFrame::new(id, &data[..n]).ok_or(LineError::TooLong(n))
}

/// Parses one log line (without its newline).
pub fn parse_line(line: &str) -> Result<LogEntry, LineError> {
    let mut fields = line.split_whitespace();
    let ts = fields.next().ok_or(LineError::MissingTimestamp)?;
    let time_us = parse_timestamp(ts)?;
    let iface = fields.next().ok_or(LineError::MissingInterface)?;
    let frame = parse_frame(fields.next().ok_or(LineError::MissingFrame)?)?;
    if let Some(extra) = fields.next() {
        return Err(LineError::TrailingText(extra.to_string()));
    }
    Ok(LogEntry {
        time_us,
        iface: iface.to_string(),
        frame,
    })
}

/// One log line in candump's format (no newline).
pub fn format_line(entry: &LogEntry) -> String {
    let mut s = String::with_capacity(48);
    let _ = write!(
        s,
        "({}.{:06}) {} {}",
        entry.time_us / 1_000_000,
        entry.time_us % 1_000_000,
        entry.iface,
        entry.frame
    );
    s
}

/// Streams entries out of a log; blank lines are skipped, line numbers count them.
pub struct LogReader<R> {
    input: R,
    line: usize,
    buf: Vec<u8>,
}

impl<R: BufRead> LogReader<R> {
    /// A reader over any buffered input.
    pub fn new(input: R) -> Self {
        Self {
            input,
            line: 0,
            buf: Vec::with_capacity(MAX_LINE_BYTES + 1),
        }
    }

    /// Reads the next line into `buf`, keeping at most `MAX_LINE_BYTES + 1` bytes of it (the
    /// rest of a longer line is read and dropped). `Ok(false)` at the end of the input.
    fn read_bounded_line(&mut self) -> io::Result<bool> {
        self.buf.clear();
        let limit = (MAX_LINE_BYTES + 1) as u64;
        let n = (&mut self.input)
            .take(limit)
            .read_until(b'\n', &mut self.buf)?;
        if n == 0 {
            return Ok(false);
        }
        if self.buf.last() != Some(&b'\n') && self.buf.len() > MAX_LINE_BYTES {
            skip_to_newline(&mut self.input)?;
        }
        Ok(true)
    }
}

/// Consumes input up to and including the next newline, without buffering it.
fn skip_to_newline(input: &mut impl BufRead) -> io::Result<()> {
    loop {
        let chunk = input.fill_buf()?;
        if chunk.is_empty() {
            return Ok(());
        }
        match chunk.iter().position(|&b| b == b'\n') {
            Some(i) => {
                input.consume(i + 1);
                return Ok(());
            }
            None => {
                let n = chunk.len();
                input.consume(n);
            }
        }
    }
}

/// The text of one raw line without its line ending, or what is wrong with it.
fn line_text(raw: &[u8]) -> Result<&str, LineError> {
    let raw = raw.strip_suffix(b"\n").unwrap_or(raw);
    let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
    if raw.len() > MAX_LINE_BYTES {
        return Err(LineError::LineTooLong);
    }
    std::str::from_utf8(raw).map_err(|e| LineError::NotUtf8(e.valid_up_to() + 1))
}

impl<R: BufRead> Iterator for LogReader<R> {
    type Item = Result<LogEntry, CandumpError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            self.line += 1;
            match self.read_bounded_line() {
                Ok(false) => return None,
                Ok(true) => {}
                Err(e) => return Some(Err(CandumpError::Io(e))),
            }
            let line = self.line;
            let at = |error| CandumpError::Line { line, error };
            let text = match line_text(&self.buf) {
                Ok(text) => text,
                Err(e) => return Some(Err(at(e))),
            };
            if text.trim().is_empty() {
                continue;
            }
            return Some(parse_line(text).map_err(at));
        }
    }
}

/// Reads a whole log file; the first malformed line stops it with its line number.
pub fn read_log(path: impl AsRef<Path>) -> Result<Vec<LogEntry>, CandumpError> {
    let file = std::fs::File::open(path)?;
    LogReader::new(io::BufReader::new(file)).collect()
}

/// Parses a whole log held in memory.
pub fn parse_log(text: &str) -> Result<Vec<LogEntry>, CandumpError> {
    LogReader::new(text.as_bytes()).collect()
}

/// Writes entries in candump's format, one per line.
pub struct LogWriter<W: Write> {
    out: W,
}

impl<W: Write> LogWriter<W> {
    /// A writer over any output (wrap files in a `BufWriter`).
    pub fn new(out: W) -> Self {
        Self { out }
    }

    /// Writes one entry.
    pub fn write(&mut self, entry: &LogEntry) -> io::Result<()> {
        self.write_frame(entry.time_us, &entry.iface, &entry.frame)
    }

    /// Writes one frame without building a [`LogEntry`] (no allocation).
    pub fn write_frame(&mut self, time_us: u64, iface: &str, frame: &CanFrame) -> io::Result<()> {
        writeln!(
            self.out,
            "({}.{:06}) {} {}",
            time_us / 1_000_000,
            time_us % 1_000_000,
            iface,
            frame
        )
    }

    /// Flushes the output.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The output back.
    pub fn into_inner(self) -> W {
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_example() {
        let e = parse_line("(1700000000.123456) vcan0 123#DEADBEEF").expect("valid line");
        assert_eq!(e.time_us, 1_700_000_000_123_456);
        assert_eq!(e.iface, "vcan0");
        assert_eq!(e.frame.raw_id(), 0x123);
        assert_eq!(e.frame.data(), &[0xDE, 0xAD, 0xBE, 0xEF]);
        assert_eq!(format_line(&e), "(1700000000.123456) vcan0 123#DEADBEEF");
    }

    #[test]
    fn extended_remote_and_empty_frames() {
        let e = parse_line("(1.000001) can0 1ABCDEF0#0011").expect("valid");
        assert!(e.frame.is_extended());
        assert_eq!(e.frame.raw_id(), 0x1ABC_DEF0);
        let r = parse_line("(0.000000) can0 7FF#R").expect("valid");
        assert!(r.frame.is_remote());
        assert_eq!(r.frame.dlc(), 0);
        let r4 = parse_line("(0.000000) can0 100#R4").expect("valid");
        assert_eq!((r4.frame.dlc(), r4.frame.is_remote()), (4, true));
        assert_eq!(format_line(&r4), "(0.000000) can0 100#R4");
        let empty = parse_line("(0.000000) can0 100#").expect("valid");
        assert_eq!(empty.frame.dlc(), 0);
    }

    #[test]
    fn malformed_lines_say_what_is_wrong() {
        let cases: &[(&str, LineError)] = &[
            ("", LineError::MissingTimestamp),
            ("vcan0 123#00", LineError::MissingTimestamp),
            (
                "(1.5) vcan0 123#00",
                LineError::BadTimestamp("(1.5)".into()),
            ),
            ("(1.000000)", LineError::MissingInterface),
            ("(1.000000) vcan0", LineError::MissingFrame),
            (
                "(1.000000) vcan0 12300",
                LineError::MissingHash("12300".into()),
            ),
            ("(1.000000) vcan0 123##1DEAD", LineError::CanFd),
            ("(1.000000) vcan0 12#00", LineError::BadId("12".into())),
            (
                "(1.000000) vcan0 800#00",
                LineError::IdOutOfRange {
                    id: 0x800,
                    bits: 11,
                },
            ),
            (
                "(1.000000) vcan0 20000000#00",
                LineError::IdOutOfRange {
                    id: 0x2000_0000,
                    bits: 29,
                },
            ),
            ("(1.000000) vcan0 123#0", LineError::BadData("0".into())),
            ("(1.000000) vcan0 123#0G", LineError::BadData("0G".into())),
            (
                "(1.000000) vcan0 123#001122334455667788",
                LineError::TooLong(9),
            ),
            (
                "(1.000000) vcan0 123#0011223344556677_9",
                LineError::TooLong(9),
            ),
            (
                "(1.000000) vcan0 123#R9",
                LineError::BadRemoteDlc("9".into()),
            ),
            (
                "(1.000000) vcan0 123#R12",
                LineError::BadRemoteDlc("12".into()),
            ),
            (
                "(1.000000) vcan0 123#00 T",
                LineError::TrailingText("T".into()),
            ),
        ];
        for (line, want) in cases {
            assert_eq!(parse_line(line).as_ref(), Err(want), "line {line:?}");
        }
    }

    #[test]
    fn reader_reports_the_line_number() {
        let text = "(1.000000) vcan0 123#00\n\n(2.000000) vcan0 123##0\n";
        let err = parse_log(text).expect_err("line 3 is CAN FD");
        let msg = err.to_string();
        assert!(
            matches!(
                err,
                CandumpError::Line {
                    line: 3,
                    error: LineError::CanFd
                }
            ),
            "{msg}"
        );
        assert!(msg.starts_with("line 3: CAN FD"), "{msg}");
    }
}

#[cfg(test)]
mod hostile_input {
    use super::*;

    // Regression: a log without newlines used to be buffered whole (`read_line` has no bound).
    #[test]
    fn an_overlong_line_is_refused_with_its_number_and_reading_goes_on() {
        let long = "(1.000000) vcan0 123#00".to_string() + &" ".repeat(MAX_LINE_BYTES);
        let text = format!("(1.000000) vcan0 123#00\n{long}\n(2.000000) vcan0 124#01\n");
        let mut reader = LogReader::new(text.as_bytes());
        assert!(reader.next().expect("line 1").is_ok());
        let err = reader.next().expect("line 2").expect_err("too long");
        assert_eq!(
            err.to_string(),
            "line 2: line longer than 256 bytes: not a candump line"
        );
        let third = reader
            .next()
            .expect("line 3")
            .expect("the next line is read whole");
        assert_eq!(third.frame.raw_id(), 0x124);
        assert!(reader.next().is_none());
        // The longest line accepted, with and without a final newline.
        let edge = format!("(1.000000) vcan0 123#00{}", " ".repeat(MAX_LINE_BYTES - 23));
        assert_eq!(edge.len(), MAX_LINE_BYTES);
        assert!(parse_log(&edge).is_ok());
        assert!(parse_log(&format!("{edge}\r\n")).is_ok());
        assert!(parse_log(&format!("{edge} ")).is_err());
    }

    // Regression: invalid UTF-8 used to come out as an I/O error without a line number.
    #[test]
    fn bytes_that_are_not_utf8_are_refused_with_line_and_byte() {
        let bytes = b"(1.000000) vcan0 123#00\n(2.0\xff0000) vcan0 123#00\n";
        let err = LogReader::new(&bytes[..])
            .collect::<Result<Vec<_>, _>>()
            .expect_err("line 2 is not text");
        assert!(
            matches!(
                err,
                CandumpError::Line {
                    line: 2,
                    error: LineError::NotUtf8(5)
                }
            ),
            "{err}"
        );
        assert_eq!(err.to_string(), "line 2: byte 5 is not UTF-8 text");
    }
}
