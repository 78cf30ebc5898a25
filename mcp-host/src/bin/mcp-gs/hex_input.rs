//! Hex text read as the bytes it stands for, as it comes: a line typed or piped in is
//! decoded when its end arrives, and memory stays bounded however long a line is. A line
//! that is not hex (a typo) is skipped and said, and reading goes on.

use std::fmt;
use std::io::{self, BufRead, Read};

/// The most bytes held back from the reader before a line ends: a longer line (a hex dump
/// on one line) is handed over in pieces of this size.
const HELD: usize = 4096;

/// How many characters of a word an error message quotes.
const QUOTED: usize = 24;

/// Reads hex text: pairs of hex digits; whitespace, `:`, `,` and `0x` prefixes between
/// bytes are ignored; `#` starts a comment to the end of the line. A read hands over the
/// bytes of one line at most (of [`HELD`] bytes of it, for a longer line).
///
/// A line that is not hex (a word that is not whole hex bytes, a character outside ASCII)
/// is skipped: none of its bytes are handed over (of a line longer than [`HELD`] bytes,
/// none after the piece that held the fault), and the read after the line's end fails
/// with an [`io::ErrorKind::InvalidData`] error holding a [`BadText`]; reading on goes
/// on after it, as if the line was not there. Text that is not text at all (control
/// bytes: a raw capture) fails likewise, and ends the reading.
pub(crate) struct HexReader<R> {
    text: R,
    parser: Parser,
    /// The end of the text was read.
    ended: bool,
    /// Bytes parsed and handed over so far of `parser.bytes`.
    taken: usize,
}

/// Hex text that could not be read: where, what was wrong, and what was skipped for it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct BadText {
    /// The line, counted from 1.
    pub(crate) line: usize,
    /// What was wrong with it.
    pub(crate) problem: String,
    /// What of the text was left unread for it.
    pub(crate) skipped: Skipped,
}

/// What of the text a [`BadText`] left unread.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Skipped {
    /// Its line; reading goes on with the next one.
    Line,
    /// The rest of its line, a line so long that its first bytes were handed over
    /// before the fault; reading goes on with the next line.
    RestOfLine,
    /// Everything after it: the text is not text, reading ends.
    Rest,
}

impl BadText {
    /// The [`BadText`] an error of a [`HexReader`] holds.
    pub(crate) fn of(error: &io::Error) -> Option<&BadText> {
        error.get_ref()?.downcast_ref()
    }

    /// Whether reading goes on after it.
    pub(crate) fn goes_on(&self) -> bool {
        self.skipped != Skipped::Rest
    }

    /// What was skipped for it, as a message says it: `line skipped`.
    pub(crate) fn skipped_note(&self) -> &'static str {
        match self.skipped {
            Skipped::Line => "line skipped",
            Skipped::RestOfLine => "rest of the line skipped",
            Skipped::Rest => "reading stopped",
        }
    }
}

impl fmt::Display for BadText {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.problem)
    }
}

impl std::error::Error for BadText {}

impl From<BadText> for io::Error {
    fn from(bad: BadText) -> Self {
        io::Error::new(io::ErrorKind::InvalidData, bad)
    }
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
    /// Bytes parsed and not yet handed over: of the line being read only.
    bytes: Vec<u8>,
    /// Bytes of the line being read were handed over already (a line longer than
    /// [`HELD`] bytes).
    handed_over: bool,
    /// What is wrong with the line being read, which is skipped to its end.
    bad: Option<BadText>,
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
    /// them within a line), or the text ends; false if it ended with none. A line that
    /// is not hex fails once its end is read.
    fn fill(&mut self) -> io::Result<bool> {
        self.parser.bytes.clear();
        self.taken = 0;
        while !self.ended {
            let chunk = self.text.fill_buf()?;
            if chunk.is_empty() {
                self.ended = true;
                self.parser.end_word();
                break;
            }
            let mut used = 0;
            let mut hand_over = false;
            let mut line_ended = false;
            for &c in chunk {
                used += 1;
                if let Err(bad) = self.parser.take(c) {
                    // Reading ends here, the line's bytes (and fault) before it left out.
                    self.ended = true;
                    self.parser.bytes.clear();
                    self.parser.bad = None;
                    return Err(bad.into());
                }
                if c == b'\n' && self.parser.bad.is_some() {
                    line_ended = true;
                    break;
                }
                let bytes = self.parser.bytes.len();
                if bytes > 0 && (c == b'\n' || bytes >= HELD) {
                    hand_over = true;
                    self.parser.handed_over = c != b'\n';
                    break;
                }
            }
            self.text.consume(used);
            if line_ended || hand_over {
                break;
            }
        }
        // The bad line ended (or the text did): it is said after what came before it.
        if let Some(bad) = self.parser.bad.take() {
            return Err(bad.into());
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
    /// Text that is not text: reading ends at it.
    fn not_text(&self, problem: impl fmt::Display) -> BadText {
        BadText {
            line: self.line + 1,
            problem: problem.to_string(),
            skipped: Skipped::Rest,
        }
    }

    /// Marks the line being read as not hex: its bytes not handed over yet are dropped,
    /// and the rest of it is skipped. The first fault of a line is the one said.
    fn fault(&mut self, problem: impl fmt::Display) {
        self.half = None;
        self.word.clear();
        self.word_len = 0;
        self.bytes.clear();
        if self.bad.is_none() {
            self.bad = Some(BadText {
                line: self.line + 1,
                problem: problem.to_string(),
                skipped: if self.handed_over {
                    Skipped::RestOfLine
                } else {
                    Skipped::Line
                },
            });
        }
    }

    /// Takes one character of the text; text that is not text at all is an error.
    fn take(&mut self, c: u8) -> Result<(), BadText> {
        match c {
            b'\n' => {
                self.end_word();
                self.comment = false;
                self.handed_over = false;
                self.line += 1;
            }
            // Control bytes: binary, not text.
            0x00..=0x08 | 0x0E..=0x1F | 0x7F => {
                return Err(self.not_text("not text (a raw capture needs no --hex)"));
            }
            // The rest of a line that is not hex, or a comment.
            _ if self.bad.is_some() || self.comment => {}
            0x80.. => self.fault(format_args!(
                "a byte outside ASCII (0x{c:02X}) is not hex text (a raw capture needs \
                 no --hex)"
            )),
            b'#' => {
                self.end_word();
                self.comment = true;
            }
            b':' | b',' => self.end_word(),
            _ if c.is_ascii_whitespace() || c == 0x0B => self.end_word(),
            _ => self.word_char(c),
        }
        Ok(())
    }

    /// Takes a character of a word: a digit of a pair, or of a `0x` prefix.
    fn word_char(&mut self, c: u8) {
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
                match pair
                    .iter()
                    .all(u8::is_ascii_hexdigit)
                    .then(|| u8::from_str_radix(text, 16).ok())
                    .flatten()
                {
                    Some(byte) => self.bytes.push(byte),
                    None => self.fault(format_args!("`{text}` is not a hex byte")),
                }
            }
        }
    }

    /// Ends the word being read, if any: a digit left without its pair is a fault.
    fn end_word(&mut self) {
        if self.half.is_some() {
            let word = std::mem::take(&mut self.word);
            self.fault(format_args!(
                "`{word}` is not whole bytes of hex (odd number of digits)"
            ));
        }
        self.word.clear();
        self.word_len = 0;
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
    fn reading_ends_at_text_that_is_not_text_its_line_left_out() {
        for line in [&b"12 34\x01"[..], b"12 zz\x01"] {
            let text = [&b"7E 00\n"[..], line, b"\n56\n"].concat();
            let mut reader = HexReader::new(&text[..]);
            let mut buf = [0u8; 16];
            assert_eq!(reader.read(&mut buf).unwrap(), 2);
            let e = reader.read(&mut buf).unwrap_err();
            assert!(e.to_string().starts_with("line 2: not text"), "{e}");
            let after = reader.read(&mut buf).map_err(|e| e.to_string());
            assert_eq!(after, Ok(0), "{:02X?}", &buf[..2]);
        }
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

    /// The bytes of `text` read to its end, and the faults said on the way.
    fn skipping(text: &[u8]) -> (Vec<u8>, Vec<BadText>) {
        let mut reader = HexReader::new(text);
        let (mut bytes, mut faults) = (Vec::new(), Vec::new());
        let mut buf = [0u8; 64];
        loop {
            match reader.read(&mut buf) {
                Ok(0) => return (bytes, faults),
                Ok(n) => bytes.extend_from_slice(&buf[..n]),
                Err(e) => {
                    let bad = BadText::of(&e).expect("a BadText").clone();
                    let goes_on = bad.goes_on();
                    faults.push(bad);
                    if !goes_on {
                        return (bytes, faults);
                    }
                }
            }
        }
    }

    #[test]
    fn a_line_that_is_not_hex_is_skipped_and_reading_goes_on() {
        // Its good bytes go with it: the line is not there.
        let (bytes, faults) = skipping(b"7E 00 02\n8A xx 06\n\n8A 06 6F\n7 # odd\n0x10");
        assert_eq!(bytes, [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x10]);
        let said: Vec<String> = faults.iter().map(ToString::to_string).collect();
        assert_eq!(
            said,
            [
                "line 2: `xx` is not a hex byte",
                "line 5: `7` is not whole bytes of hex (odd number of digits)",
            ]
        );
        assert!(faults.iter().all(|bad| bad.skipped == Skipped::Line));
        // The first fault of a line is said, once; a last line without its end too.
        let (bytes, faults) = skipping("7E\nzz é 0\n6F zz".as_bytes());
        assert_eq!(bytes, [0x7E]);
        let said: Vec<String> = faults.iter().map(ToString::to_string).collect();
        assert_eq!(
            said,
            [
                "line 2: `zz` is not a hex byte",
                "line 3: `zz` is not a hex byte"
            ]
        );
        // Text that is not text ends the reading.
        let (bytes, faults) = skipping(b"zz\n7E\n\x00\x01\n7E\n");
        assert_eq!(bytes, [0x7E]);
        assert_eq!(faults.len(), 2);
        assert_eq!(faults[1].skipped, Skipped::Rest);
        assert_eq!(
            faults[1].to_string(),
            "line 3: not text (a raw capture needs no --hex)"
        );
    }

    #[test]
    fn a_long_line_that_is_not_hex_keeps_what_was_handed_over() {
        let text = format!("{} zz {}\n7e\n", "01".repeat(HELD + 10), "02".repeat(5));
        let (bytes, faults) = skipping(text.as_bytes());
        let mut expected = vec![0x01; HELD];
        expected.push(0x7E);
        assert_eq!(bytes, expected);
        assert_eq!(faults.len(), 1);
        assert_eq!(faults[0].skipped, Skipped::RestOfLine);
        assert_eq!(faults[0].skipped_note(), "rest of the line skipped");
    }
}
