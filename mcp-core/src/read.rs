//! nom parsers for the protocol's field types (little-endian).

use nom::{
    IResult, Parser,
    bytes::complete::take,
    combinator::map,
    number::complete::{le_f32, le_u32, u8 as byte},
};

use crate::address::Address;

/// Result of a field parser. Length checks come before these parsers run, so their
/// failures carry no detail.
pub(crate) type Res<'a, T> = IResult<&'a [u8], T, ()>;

/// One byte.
pub(crate) fn u8(i: &[u8]) -> Res<'_, u8> {
    byte(i)
}

/// A little-endian `u32`.
pub(crate) fn u32(i: &[u8]) -> Res<'_, u32> {
    le_u32(i)
}

/// A little-endian IEEE-754 binary32.
pub(crate) fn f32(i: &[u8]) -> Res<'_, f32> {
    le_f32(i)
}

/// An on/off byte: any non-zero value is on.
pub(crate) fn on_off(i: &[u8]) -> Res<'_, bool> {
    map(byte, |b| b != 0).parse(i)
}

/// An 8-byte address.
pub(crate) fn address(i: &[u8]) -> Res<'_, Address> {
    let (rest, bytes) = take(8usize).parse(i)?;
    let mut out = [0; 8];
    out.copy_from_slice(bytes);
    Ok((rest, Address(out)))
}
