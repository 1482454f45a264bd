//! Hostile variants of a valid file: arbitrary bytes, and mutations of the valid bytes (bit
//! flips, truncations, insertions, deletions, numbers replaced with huge, negative or NaN values,
//! duplicated lines so keys and sections repeat). Every runner is seeded so CI is deterministic.

use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed};

/// A deterministic configuration: `cases` cases from a fixed ChaCha seed, no persistence file.
pub fn seeded(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 2_000,
        ..Config::default()
    }
}

/// Values a number in a file is replaced with: out of every range, of the wrong type, or no
/// number at all.
const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "-0.0",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e309",
    "-1e309",
    "1e-320",
    "4294967296",
    "1099511627776",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "18446744073709551616",
    "-9223372036854775809",
    "99999999999999999999999999999",
    "0x10",
    "1_000",
    "\"7\"",
    "[1, 2]",
    "",
];

/// One change to a file.
#[derive(Debug, Clone)]
pub enum Mutation {
    /// XOR one byte with a non-zero mask.
    Flip(Index, u8),
    /// Cut the file.
    Truncate(Index),
    /// Insert bytes.
    Insert(Index, Vec<u8>),
    /// Delete up to 16 bytes.
    Delete(Index, u8),
    /// Replace one number (a run of digits, with its sign, dot and exponent) with a hostile one.
    Number(Index, Index),
    /// Repeat one line right after itself.
    DuplicateLine(Index),
}

/// Spans of the numbers in `bytes`: a digit run with an optional leading `-`, dots and exponent.
fn number_spans(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i].is_ascii_digit() {
            let start = if i > 0 && bytes[i - 1] == b'-' {
                i - 1
            } else {
                i
            };
            let mut end = i;
            while end < bytes.len() && (bytes[end].is_ascii_digit() || b".eE".contains(&bytes[end]))
            {
                end += 1;
            }
            spans.push((start, end));
            i = end;
        } else {
            i += 1;
        }
    }
    spans
}

/// Byte ranges of the lines of `bytes`, newlines included.
fn line_spans(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            spans.push((start, i + 1));
            start = i + 1;
        }
    }
    if start < bytes.len() {
        spans.push((start, bytes.len()));
    }
    spans
}

impl Mutation {
    /// Applies the change (indices wrap to the current length; an empty file stays as it is for
    /// the changes that need a position inside it).
    pub fn apply(&self, bytes: &mut Vec<u8>) {
        let len = bytes.len();
        match self {
            Mutation::Flip(at, mask) if len > 0 => bytes[at.index(len)] ^= (*mask).max(1),
            Mutation::Truncate(at) => bytes.truncate(at.index(len + 1)),
            Mutation::Insert(at, new) => {
                let at = at.index(len + 1);
                bytes.splice(at..at, new.iter().copied());
            }
            Mutation::Delete(at, n) if len > 0 => {
                let at = at.index(len);
                bytes.drain(at..(at + *n as usize % 16 + 1).min(len));
            }
            Mutation::Number(which, with) => {
                let spans = number_spans(bytes);
                if !spans.is_empty() {
                    let (s, e) = spans[which.index(spans.len())];
                    let new = NUMBERS[with.index(NUMBERS.len())].as_bytes();
                    bytes.splice(s..e, new.iter().copied());
                }
            }
            Mutation::DuplicateLine(which) => {
                let spans = line_spans(bytes);
                if !spans.is_empty() {
                    let (s, e) = spans[which.index(spans.len())];
                    let mut line = bytes[s..e].to_vec();
                    if line.last() != Some(&b'\n') {
                        line.insert(0, b'\n');
                    }
                    bytes.splice(e..e, line);
                }
            }
            _ => {}
        }
    }
}

/// Bytes that are likely to matter in text formats, mixed with arbitrary ones.
fn inserted_bytes() -> impl Strategy<Value = Vec<u8>> {
    let text = prop::sample::select(b"\n\r\t #=[]{}\",.:-_()0123456789eE\xff\x00\\'ntfR".to_vec());
    prop::collection::vec(prop_oneof![3 => text, 1 => any::<u8>()], 1..12)
}

/// One mutation.
pub fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        3 => (any::<Index>(), any::<u8>()).prop_map(|(i, m)| Mutation::Flip(i, m)),
        1 => any::<Index>().prop_map(Mutation::Truncate),
        2 => (any::<Index>(), inserted_bytes()).prop_map(|(i, b)| Mutation::Insert(i, b)),
        1 => (any::<Index>(), any::<u8>()).prop_map(|(i, n)| Mutation::Delete(i, n)),
        4 => (any::<Index>(), any::<Index>()).prop_map(|(i, w)| Mutation::Number(i, w)),
        2 => any::<Index>().prop_map(Mutation::DuplicateLine),
    ]
}

/// `valid` after one to three mutations (one in half of the cases, so most files stay close
/// enough to valid to reach the checks behind the parser).
pub fn mutated(valid: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let count = prop_oneof![Just(1usize), 2usize..4];
    count
        .prop_flat_map(|n| prop::collection::vec(mutation(), n))
        .prop_map(move |ms| {
            let mut bytes = valid.clone();
            for m in &ms {
                m.apply(&mut bytes);
            }
            bytes
        })
}

/// Arbitrary bytes, or arbitrary text-like bytes (so parsers get past their first check).
pub fn arbitrary_bytes(max: usize) -> impl Strategy<Value = Vec<u8>> {
    prop_oneof![
        prop::collection::vec(any::<u8>(), 0..max),
        prop::collection::vec(
            prop::sample::select(b"\n #=[]{}\",.:-_()0123456789abcdefxyzR\"".to_vec()),
            0..max
        ),
    ]
}

/// The 1-based line numbers a text mentions as `line N` (also `line N, column M`).
pub fn mentioned_lines(message: &str) -> Vec<usize> {
    message
        .match_indices("line ")
        .filter_map(|(i, _)| {
            let rest = &message[i + 5..];
            let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
            digits.parse().ok()
        })
        .collect()
}

/// Whether `message` names at least one line, and only lines of `bytes`.
pub fn names_lines_of(message: &str, bytes: &[u8]) -> bool {
    let named = mentioned_lines(message);
    let lines = line_count(bytes);
    !named.is_empty() && named.iter().all(|l| (1..=lines).contains(l))
}

/// Number of lines of `bytes` as an editor counts them (at least 1).
pub fn line_count(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count() + 1
}
