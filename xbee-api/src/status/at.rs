//! Status of a local or remote AT command response.

code_enum! {
    /// Command status of an AT Command Response (0x88) or Remote AT Command Response
    /// (0x97).
    pub enum AtStatus {
        /// 0x00: OK.
        Ok = 0x00 => "ok",
        /// 0x01: ERROR.
        Error = 0x01 => "error",
        /// 0x02: invalid command.
        InvalidCommand = 0x02 => "invalid_command",
        /// 0x03: invalid parameter.
        InvalidParameter = 0x03 => "invalid_parameter",
        /// 0x04: transmission failure (remote command not delivered).
        TxFailure = 0x04 => "tx_failure",
    }
}

impl AtStatus {
    /// Whether the command succeeded.
    pub const fn is_ok(self) -> bool {
        matches!(self, Self::Ok)
    }
}
