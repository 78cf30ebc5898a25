//! Status of a local or remote AT command response.

code_enum! {
    /// Command status of an AT Command Response (0x88) or Remote AT Command Response
    /// (0x97).
    ///
    /// Test success with [`is_ok`](Self::is_ok), not `== AtStatus::Ok`: some firmware
    /// sets upper bits of the code ([`meaning`](Self::meaning)).
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
        /// 0x0B: no secure session: the remote radio takes remote commands only over a
        /// secure session, which must be established first.
        NoSecureSession = 0x0B => "no_secure_session",
        /// 0x0C: encryption error.
        EncryptionError = 0x0C => "encryption_error",
        /// 0x0D: command sent insecurely: a secure session exists, but the command was
        /// sent without the secure session option (bit 4).
        CommandSentInsecurely = 0x0D => "command_sent_insecurely",
    }
}

impl AtStatus {
    /// What the status says, read from the low four bits of its code as Digi's own
    /// software reads it: some firmware sets upper bits in an answer (0x40 for an OK),
    /// which Digi's XCTU and xbee-python ignore. The status itself keeps the whole code
    /// as received (`AtStatus::Unknown(0x40)`), so that a frame encodes back to the
    /// same bytes.
    ///
    /// ```
    /// use xbee_api::AtStatus;
    ///
    /// assert_eq!(AtStatus::from(0x40).meaning(), AtStatus::Ok);
    /// assert_eq!(AtStatus::from(0x43).meaning(), AtStatus::InvalidParameter);
    /// assert!(AtStatus::from(0x40).is_ok());
    /// assert_eq!(u8::from(AtStatus::from(0x40)), 0x40);
    /// ```
    pub const fn meaning(self) -> Self {
        match self {
            Self::Unknown(code) => match code & 0x0F {
                0x00 => Self::Ok,
                0x01 => Self::Error,
                0x02 => Self::InvalidCommand,
                0x03 => Self::InvalidParameter,
                0x04 => Self::TxFailure,
                0x0B => Self::NoSecureSession,
                0x0C => Self::EncryptionError,
                0x0D => Self::CommandSentInsecurely,
                _ => self,
            },
            named => named,
        }
    }

    /// Whether the command succeeded: the [`meaning`](Self::meaning) is OK.
    pub const fn is_ok(self) -> bool {
        matches!(self.meaning(), Self::Ok)
    }
}
