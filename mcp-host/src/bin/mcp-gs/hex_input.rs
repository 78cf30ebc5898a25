//! Hex text read as the bytes it stands for, a line at a time, so that a capture typed
//! or piped in as hex is decoded as it comes.

use std::io::{self, BufRead, Read};

/// Reads hex text: pairs of hex digits; whitespace, `:`, `,` and `0x` prefixes between
/// bytes are ignored; `#` starts a comment to the end of the line. Each read hands over
/// the bytes of one line at most; text that is not hex is an [`io::ErrorKind::InvalidData`]
/// error naming the line.
pub(crate) struct HexReader<R> {
    text: R,
    line: String,
    line_no: usize,
    bytes: Vec<u8>,
    taken: usize,
}

impl<R: BufRead> HexReader<R> {
    pub(crate) fn new(text: R) -> Self {
        HexReader {
            text,
            line: String::new(),
            line_no: 0,
            bytes: Vec::new(),
            taken: 0,
        }
    }

    /// The bytes of the next line that has any; false at the end of the text.
    fn next_line(&mut self) -> io::Result<bool> {
        loop {
            self.line.clear();
            let read = self.text.read_line(&mut self.line).map_err(|e| {
                if e.kind() == io::ErrorKind::InvalidData {
                    // Not UTF-8: binary, not hex text.
                    io::Error::new(
                        e.kind(),
                        format!(
                            "line {}: not text (a raw capture needs no --hex)",
                            self.line_no + 1
                        ),
                    )
                } else {
                    e
                }
            })?;
            if read == 0 {
                return Ok(false);
            }
            self.line_no += 1;
            self.bytes.clear();
            self.taken = 0;
            parse_line(&self.line, self.line_no, &mut self.bytes)?;
            if !self.bytes.is_empty() {
                return Ok(true);
            }
        }
    }
}

impl<R: BufRead> Read for HexReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.taken == self.bytes.len() && !self.next_line()? {
            return Ok(0);
        }
        let rest = &self.bytes[self.taken..];
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.taken += n;
        Ok(n)
    }
}

/// Appends the bytes that line `line_no` of hex text stands for to `bytes`.
fn parse_line(line: &str, line_no: usize, bytes: &mut Vec<u8>) -> io::Result<()> {
    let invalid = |message: String| io::Error::new(io::ErrorKind::InvalidData, message);
    let line = line.split('#').next().unwrap_or("");
    for word in line.split(|c: char| c.is_whitespace() || c == ':' || c == ',') {
        let word = word
            .strip_prefix("0x")
            .or_else(|| word.strip_prefix("0X"))
            .unwrap_or(word);
        if word.len() % 2 != 0 {
            return Err(invalid(format!(
                "line {line_no}: `{word}` is not whole bytes of hex (odd number of digits)"
            )));
        }
        for pair in word.as_bytes().chunks(2) {
            let text = std::str::from_utf8(pair).unwrap_or("??");
            let byte = u8::from_str_radix(text, 16)
                .map_err(|_| invalid(format!("line {line_no}: `{text}` is not a hex byte")))?;
            bytes.push(byte);
        }
    }
    Ok(())
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
}
