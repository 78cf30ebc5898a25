//! Hex text read as the bytes it stands for, as it comes: a line typed or piped in is
//! decoded when its end arrives, and memory stays bounded however long a line is.

use std::io::{self, BufRead, Read};

/// The most bytes held back from the reader before a line ends: a longer line (a hex dump
/// on one line) is handed over in pieces of this size.
const HELD: usize = 4096;

/// How many characters of a word an error message quotes.
const QUOTED: usize = 24;

/// Reads hex text: pairs of hex digits; whitespace, `:`, `,` and `0x` prefixes between
/// bytes are ignored; `#` starts a comment to the end of the line. A read hands over the
/// bytes of one line at most (of [`HELD`] bytes of it, for a longer line); text that is
/// not hex is an [`io::ErrorKind::InvalidData`] error naming the line.
pub(crate) struct HexReader<R> {
    text: R,
    parser: Parser,
    /// The end of the text was read.
    ended: bool,
    /// Bytes parsed and handed over so far of `parser.bytes`.
    taken: usize,
}

/// Where reading hex text is, a character at a time.
#[derive(Default)]
struct Parser {
    /// The line being read, counted from 0.
    line: usize,
    /// In a `#` comment.
    comment: bool,
    /// The word being read, as far as an error message quotes it.
    word: String,
    /// Characters of the word read so far.
    word_len: usize,
    /// The first digit of a pair whose second has not come yet.
    half: Option<u8>,
    /// Bytes parsed and not yet handed over.
    bytes: Vec<u8>,
}

impl<R: BufRead> HexReader<R> {
    pub(crate) fn new(text: R) -> Self {
        HexReader {
            text,
            parser: Parser::default(),
            ended: false,
            taken: 0,
        }
    }

    /// Parses text until bytes are there to hand over at a line's end (or [`HELD`] of
    /// them within a line), or the text ends; false if it ended with none.
    fn fill(&mut self) -> io::Result<bool> {
        self.parser.bytes.clear();
        self.taken = 0;
        while !self.ended {
            let chunk = self.text.fill_buf()?;
            if chunk.is_empty() {
                self.ended = true;
                self.parser.end_word()?;
                break;
            }
            let mut used = 0;
            let mut hand_over = false;
            for &c in chunk {
                used += 1;
                self.parser.take(c)?;
                let bytes = self.parser.bytes.len();
                if bytes > 0 && (c == b'\n' || bytes >= HELD) {
                    hand_over = true;
                    break;
                }
            }
            self.text.consume(used);
            if hand_over {
                break;
            }
        }
        Ok(!self.parser.bytes.is_empty())
    }
}

impl<R: BufRead> Read for HexReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.taken == self.parser.bytes.len() && !self.fill()? {
            return Ok(0);
        }
        let rest = &self.parser.bytes[self.taken..];
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.taken += n;
        Ok(n)
    }
}

impl Parser {
    fn invalid(&self, message: impl std::fmt::Display) -> io::Error {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("line {}: {message}", self.line + 1),
        )
    }

    /// Takes one character of the text.
    fn take(&mut self, c: u8) -> io::Result<()> {
        match c {
            b'\n' => {
                self.end_word()?;
                self.comment = false;
                self.line += 1;
            }
            // Control bytes: binary, not text.
            0x00..=0x08 | 0x0E..=0x1F | 0x7F => {
                return Err(self.invalid("not text (a raw capture needs no --hex)"));
            }
            _ if self.comment => {}
            0x80.. => {
                return Err(self.invalid(format_args!(
                    "a byte outside ASCII (0x{c:02X}) is not hex text (a raw capture needs \
                     no --hex)"
                )));
            }
            b'#' => {
                self.end_word()?;
                self.comment = true;
            }
            b':' | b',' => self.end_word()?,
            _ if c.is_ascii_whitespace() || c == 0x0B => self.end_word()?,
            _ => self.word_char(c)?,
        }
        Ok(())
    }

    /// Takes a character of a word: a digit of a pair, or of a `0x` prefix.
    fn word_char(&mut self, c: u8) -> io::Result<()> {
        if self.word_len < QUOTED {
            self.word.push(char::from(c));
        } else if self.word_len == QUOTED {
            self.word.push('…');
        }
        self.word_len += 1;
        match self.half.take() {
            None => self.half = Some(c),
            Some(b'0') if self.word_len == 2 && matches!(c, b'x' | b'X') => {}
            Some(first) => {
                let pair = [first, c];
                let text = std::str::from_utf8(&pair).unwrap_or("??");
                // Two hex digits: `from_str_radix` alone would take a sign, `+6`.
                let byte = pair
                    .iter()
                    .all(u8::is_ascii_hexdigit)
                    .then(|| u8::from_str_radix(text, 16).ok())
                    .flatten()
                    .ok_or_else(|| self.invalid(format_args!("`{text}` is not a hex byte")))?;
                self.bytes.push(byte);
            }
        }
        Ok(())
    }

    /// Ends the word being read, if any: a digit left without its pair is an error.
    fn end_word(&mut self) -> io::Result<()> {
        if self.half.is_some() {
            return Err(self.invalid(format_args!(
                "`{}` is not whole bytes of hex (odd number of digits)",
                self.word
            )));
        }
        self.word.clear();
        self.word_len = 0;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> io::Result<Vec<u8>> {
        let mut bytes = Vec::new();
        HexReader::new(text.as_bytes()).read_to_end(&mut bytes)?;
        Ok(bytes)
    }

    #[test]
    fn separators_prefixes_and_comments() {
        assert_eq!(
            all("7E 00:02,8A\n# a comment\n0x06 6f # checksum\n\n").unwrap(),
            [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]
        );
        assert_eq!(
            all("7e00028a066f").unwrap(),
            [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]
        );
        assert!(all("# nothing\n").unwrap().is_empty());
    }

    #[test]
    fn errors_name_the_line() {
        let e = all("7E\n00 0\n").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        assert!(
            e.to_string().starts_with("line 2: `0` is not whole bytes"),
            "{e}"
        );
        let e = all("7E zz\n").unwrap_err();
        assert_eq!(e.to_string(), "line 1: `zz` is not a hex byte");
        // A sign is no digit, though Rust's number parser takes one.
        let e = all("7E 00 02 8A +6 6F\n").unwrap_err();
        assert_eq!(e.to_string(), "line 1: `+6` is not a hex byte");
        let e = all("0x+6\n").unwrap_err();
        assert_eq!(e.to_string(), "line 1: `+6` is not a hex byte");
        let mut bytes = Vec::new();
        let e = HexReader::new(&b"7E 00\n\x7E\x00\x02\x8A\xFF\n"[..])
            .read_to_end(&mut bytes)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 2: not text (a raw capture needs no --hex)"
        );
    }

    #[test]
    fn a_read_ends_with_its_line() {
        // What a pipe fed a line at a time gives: each read stops at a line's end.
        let mut reader = HexReader::new("7E 00 02\n8A 06 6F\n".as_bytes());
        let mut buf = [0u8; 16];
        assert_eq!(reader.read(&mut buf).unwrap(), 3);
        assert_eq!(reader.read(&mut buf[..2]).unwrap(), 2);
        assert_eq!(buf[..2], [0x8A, 0x06]);
        assert_eq!(reader.read(&mut buf).unwrap(), 1);
        assert_eq!(reader.read(&mut buf).unwrap(), 0);
    }

    #[test]
    fn a_long_line_is_read_in_pieces() {
        // A hex dump on one line of 1 MB of text: read a piece at a time, not whole.
        let text = "7e".repeat(500_000);
        let mut input = io::Cursor::new(text.as_bytes());
        let mut reader = HexReader::new(&mut input);
        let mut buf = vec![0u8; 100_000];
        assert_eq!(reader.read(&mut buf).unwrap(), HELD);
        assert!(reader.parser.bytes.capacity() <= HELD);
        let mut rest = Vec::new();
        reader.read_to_end(&mut rest).unwrap();
        assert_eq!(rest.len(), 500_000 - HELD);
        assert!(rest.iter().all(|&b| b == 0x7E));
        assert!(reader.parser.bytes.capacity() <= HELD);

        // Only so much of the text was read for the first piece.
        let mut input = io::BufReader::with_capacity(64, text.as_bytes());
        let mut reader = HexReader::new(&mut input);
        assert_eq!(reader.read(&mut buf).unwrap(), HELD);
        drop(reader);
        assert_eq!(input.into_inner().len(), text.len() - 2 * HELD);
    }

    #[test]
    fn words_are_quoted_short_and_comments_may_be_any_text() {
        let long = format!("7E {}0\n", "a".repeat(40));
        let e = all(&long).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "line 1: `{}…` is not whole bytes of hex (odd number of digits)",
                "a".repeat(24)
            )
        );
        // An odd word at the very end, with no line end after it.
        let e = all("7E\n0x7").unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 2: `0x7` is not whole bytes of hex (odd number of digits)"
        );
        assert_eq!(all("0X7e # café, naïve\r\n0x\t8a").unwrap(), [0x7E, 0x8A]);
        let e = all("7E é").unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 1: a byte outside ASCII (0xC3) is not hex text (a raw capture needs no --hex)"
        );
    }
}
