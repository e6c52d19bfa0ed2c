//! The lexer's word rule: which bytes separate tokens and which continue a word. The syntax
//! tree uses it too, to find where a number of a compact list ends.

use nom::bytes::complete::take_while1;
use nom::{IResult, Parser};

/// Whether `byte` separates tokens: blanks, control characters and the comma.
#[inline]
pub(crate) fn is_space(byte: u8) -> bool {
    byte <= b' ' || byte == b','
}

/// Whether `byte` may continue a word.
#[inline]
fn is_word_byte(byte: u8) -> bool {
    !is_space(byte) && !matches!(byte, b'{' | b'}' | b'[' | b']' | b'"' | b'#')
}

fn word(input: &[u8]) -> IResult<&[u8], &[u8]> {
    take_while1(is_word_byte).parse(input)
}

/// Length of the word starting at `bytes[0]` (0 if none starts there).
pub(crate) fn word_len(bytes: &[u8]) -> usize {
    word(bytes).map(|(_, w)| w.len()).unwrap_or(0)
}
