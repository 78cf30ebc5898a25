//! The API mode of a [`Decoder`](crate::Decoder) as its type gives it: at run time or
//! fixed at compile time.

use crate::ApiMode;

mod sealed {
    pub trait Sealed {}
    impl Sealed for super::AnyMode {}
    impl Sealed for super::Mode1 {}
    impl Sealed for super::Mode2 {}
}

/// Where a [`Decoder`](crate::Decoder) takes its API mode from: [`AnyMode`], the
/// default, from its constructor at run time; [`Mode1`] and [`Mode2`] from its type.
/// It is the decoder's second parameter: `Decoder<N>` is `Decoder<N, AnyMode>`, and
/// `Decoder<DEFAULT_CAPACITY, Mode2>` is the default buffer in a fixed mode 2.
///
/// Sealed: these three are all there is.
pub trait DecoderMode:
    sealed::Sealed
    + Copy
    + Default
    + core::fmt::Debug
    + PartialEq
    + Eq
    + core::hash::Hash
    + Send
    + Sync
    + 'static
{
    /// The mode of every decoder of this type; `None` for [`AnyMode`], whose decoders
    /// are each given theirs.
    const FIXED: Option<ApiMode>;
}

/// A [`DecoderMode`] fixed at compile time: [`Mode1`] or [`Mode2`] (sealed, as
/// `DecoderMode` is).
#[diagnostic::on_unimplemented(
    message = "`{Self}` does not fix the API mode in the decoder's type",
    label = "the mode is given at run time here",
    note = "a type that leaves its mode out takes `AnyMode` (`Decoder<N>` is \
            `Decoder<N, AnyMode>`, `FrameReader<R, N>` is `FrameReader<R, N, AnyMode>`): \
            make it with `new(reader, ApiMode::...)` or `Decoder::new(ApiMode::...)`, or \
            name the mode in the type, `Mode1` or `Mode2`"
)]
pub trait FixedMode: DecoderMode {
    /// The mode.
    const MODE: ApiMode;
}

/// The API mode is a value, given to [`Decoder::new`](crate::Decoder::new): one decoder
/// type reads both modes, and a program that links it carries the code of both.
///
/// The default, for hosts, where the mode is a setting of the radio read at run time.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct AnyMode;

/// API mode 1 (`AP=1`, unescaped), fixed at compile time: the decoder carries no mode 2
/// code. Made with [`Decoder::fixed`](crate::Decoder::fixed). Its mode as a value,
/// for buffer sizes and encoders, is `Mode1::MODE` (`ApiMode::Unescaped`), with
/// [`FixedMode`] in scope.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Mode1;

/// API mode 2 (`AP=2`, escaped), fixed at compile time: the decoder carries no mode 1
/// code. Made with [`Decoder::fixed`](crate::Decoder::fixed). Its mode as a value,
/// for buffer sizes and encoders, is `Mode2::MODE` (`ApiMode::Escaped`), with
/// [`FixedMode`] in scope.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Mode2;

impl DecoderMode for AnyMode {
    const FIXED: Option<ApiMode> = None;
}

impl DecoderMode for Mode1 {
    const FIXED: Option<ApiMode> = Some(Self::MODE);
}

impl DecoderMode for Mode2 {
    const FIXED: Option<ApiMode> = Some(Self::MODE);
}

impl FixedMode for Mode1 {
    const MODE: ApiMode = ApiMode::Unescaped;
}

impl FixedMode for Mode2 {
    const MODE: ApiMode = ApiMode::Escaped;
}

/// The mode a [`Mode1`] decoder reads: `ApiMode::from(Mode1)` is
/// [`ApiMode::Unescaped`].
impl From<Mode1> for ApiMode {
    fn from(_: Mode1) -> ApiMode {
        Mode1::MODE
    }
}

/// The mode a [`Mode2`] decoder reads: `ApiMode::from(Mode2)` is [`ApiMode::Escaped`].
///
/// ```
/// use xbee_api::{ApiMode, Mode2};
/// assert_eq!(ApiMode::from(Mode2), ApiMode::Escaped);
/// ```
impl From<Mode2> for ApiMode {
    fn from(_: Mode2) -> ApiMode {
        Mode2::MODE
    }
}
