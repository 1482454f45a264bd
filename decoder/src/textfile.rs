//! Reading a text file (`session.toml`, `handd.toml`): bytes that are not UTF-8 are refused
//! with the line and column of the first bad byte, which `read_to_string` does not say.

use std::io;
use std::path::Path;

/// The 1-based line and column (in bytes) of `bytes`' first byte that is not UTF-8 text.
pub fn first_non_utf8(bytes: &[u8]) -> Option<(usize, usize)> {
    let at = std::str::from_utf8(bytes).err()?.valid_up_to();
    let before = &bytes[..at];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    Some((line, at - line_start + 1))
}

/// The text of `bytes`, or an `InvalidData` error naming where it stops being UTF-8.
pub fn utf8_text(bytes: Vec<u8>) -> io::Result<String> {
    String::from_utf8(bytes).map_err(|e| {
        let (line, column) = first_non_utf8(e.as_bytes()).unwrap_or((1, 1));
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("not UTF-8 text at line {line}, column {column}"),
        )
    })
}

/// Reads a whole text file; see [`utf8_text`].
pub fn read_text(path: &Path) -> io::Result<String> {
    utf8_text(std::fs::read(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_bad_byte_is_located() {
        assert_eq!(first_non_utf8(b"a = 1\n"), None);
        assert_eq!(first_non_utf8(b"\xff"), Some((1, 1)));
        assert_eq!(first_non_utf8(b"a = 1\nb = \"\xc3\x28\"\n"), Some((2, 6)));
        assert_eq!(first_non_utf8("é\n\nxé\u{80}".as_bytes()), None);
        assert_eq!(first_non_utf8(b"\n\nab\xe2\x82"), Some((3, 3)));
        let e = utf8_text(b"ok\nok\xfe".to_vec()).expect_err("not text");
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert_eq!(e.to_string(), "not UTF-8 text at line 2, column 3");
        assert_eq!(utf8_text(b"ok".to_vec()).expect("text"), "ok");
    }
}
