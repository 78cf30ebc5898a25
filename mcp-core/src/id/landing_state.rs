use super::id_enum;

id_enum! {
    /// Landing state identifier (table 27). Bytes 0x05-0xFF are valid on the wire and
    /// decode as `Unknown`.
    ///
    /// ```
    /// use mcp_core::LandingState;
    /// assert_eq!(LandingState::from(0), LandingState::OnGround);
    /// assert_eq!(LandingState::TakeOff.name(), Some("take_off"));
    /// ```
    LandingState, "landing state" {
        /// On the ground.
        OnGround = 0x00 => "on_ground",
        /// Landing.
        Landing = 0x01 => "landing",
        /// Stabilization.
        Stabilization = 0x02 => "stabilization",
        /// Taking off.
        TakeOff = 0x03 => "take_off",
        /// In flight.
        Flight = 0x04 => "flight",
    }
}
