//! `mcp-gs decode --hex`: hex text read as the bytes it stands for (`HexReader`, the
//! binary's `hex_input` module, compiled in here from its source file). The text is
//! whatever a user pipes in: a typo, a dump with comments, a raw capture by mistake.
//!
//! Input: byte 0 sets the text reader's buffer (1-64 bytes), byte 1 the size of each
//! read (1-64 bytes); the rest is the text.
//!
//! Checks, against a plain line-by-line reading of the whole text: no panic, memory
//! bounded; the bytes handed over are exactly those of the lines that are hex (a line
//! whose fault comes after `HELD` bytes of it hands those over first); each line that
//! is not hex fails once, with its number and `Line` (or `RestOfLine`), and reading goes
//! on; text with a control byte fails there with `Rest`, and reading ends.
#![no_main]

#[allow(dead_code)]
#[path = "../../mcp-host/src/bin/mcp-gs/hex_input.rs"]
mod hex_input;

use std::io::{BufReader, Read};

use hex_input::{BadText, HexReader, Skipped};
use libfuzzer_sys::fuzz_target;

/// `hex_input::HELD`.
const HELD: usize = 4096;

#[derive(Debug, PartialEq, Eq)]
enum Out {
    Byte(u8),
    Bad(usize, Skipped),
}

fn is_control(c: u8) -> bool {
    matches!(c, 0x00..=0x08 | 0x0E..=0x1F | 0x7F)
}

fn is_separator(c: u8) -> bool {
    c.is_ascii_whitespace() || matches!(c, 0x0B | b':' | b',')
}

/// One line's bytes, and if it is not hex, how many of them came before its first
/// fault.
fn line_bytes(line: &[u8]) -> (Vec<u8>, Option<usize>) {
    let code = match line.iter().position(|&c| c == b'#') {
        Some(at) => &line[..at],
        None => line,
    };
    let mut bytes = Vec::new();
    for word in code.split(|&c| is_separator(c)) {
        let digits = match word {
            [b'0', b'x' | b'X', rest @ ..] => rest,
            _ => word,
        };
        for pair in digits.chunks(2) {
            match pair {
                [a, b] if a.is_ascii_hexdigit() && b.is_ascii_hexdigit() => {
                    let text = std::str::from_utf8(pair).unwrap();
                    bytes.push(u8::from_str_radix(text, 16).unwrap());
                }
                // A character outside ASCII, a pair that is not hex, or one digit alone.
                _ => {
                    let n = bytes.len();
                    return (bytes, Some(n));
                }
            }
        }
    }
    (bytes, None)
}

fn reference(text: &[u8]) -> Vec<Out> {
    let mut out = Vec::new();
    for (n, line) in text.split(|&c| c == b'\n').enumerate() {
        let number = n + 1;
        if let Some(at) = line.iter().position(|&c| is_control(c)) {
            let (bytes, fault) = line_bytes(&line[..at]);
            let handed = fault.unwrap_or(bytes.len()) / HELD * HELD;
            out.extend(bytes[..handed].iter().map(|&b| Out::Byte(b)));
            out.push(Out::Bad(number, Skipped::Rest));
            return out;
        }
        let (bytes, fault) = line_bytes(line);
        match fault {
            None => out.extend(bytes.iter().map(|&b| Out::Byte(b))),
            Some(k) => {
                let handed = k / HELD * HELD;
                out.extend(bytes[..handed].iter().map(|&b| Out::Byte(b)));
                let skipped = if handed > 0 {
                    Skipped::RestOfLine
                } else {
                    Skipped::Line
                };
                out.push(Out::Bad(number, skipped));
            }
        }
    }
    out
}

fuzz_target!(|input: &[u8]| {
    let [a, b, text @ ..] = input else {
        return;
    };
    let capacity = 1 + usize::from(a % 64);
    let read_size = 1 + usize::from(b % 64);
    let mut reader = HexReader::new(BufReader::with_capacity(capacity, text));
    let mut out = Vec::new();
    let mut buf = vec![0u8; read_size];
    // Each read hands over a byte or ends a line, or the text.
    for _ in 0..2 * text.len() + 4 {
        match reader.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => out.extend(buf[..n].iter().map(|&b| Out::Byte(b))),
            Err(error) => {
                let bad = BadText::of(&error).expect("an error of hex text holds a BadText");
                assert!(!bad.problem.is_empty());
                out.push(Out::Bad(bad.line, bad.skipped));
                if !bad.goes_on() {
                    // Reading has ended: nothing more comes, no byte and no error.
                    for _ in 0..3 {
                        assert_eq!(reader.read(&mut buf).ok(), Some(0), "read after the end");
                    }
                    break;
                }
            }
        }
    }
    let want = reference(text);
    assert_eq!(out, want, "hex text read otherwise than line by line");
});
