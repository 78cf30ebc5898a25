use super::id_enum;

id_enum! {
    /// Packet category, the first byte of every packet (specification tables 1 and 25).
    ///
    /// ```
    /// use mcp_core::Category;
    /// assert_eq!(Category::from(b'c'), Category::Command);
    /// assert_eq!(Category::Warning.to_string(), "warning");
    /// assert_eq!("report".parse::<Category>(), Ok(Category::Report));
    /// assert_eq!(Category::from(0x2a).to_string(), "unknown(0x2a)");
    /// ```
    Category, "packet category" {
        /// `c`: packets that control the MAV.
        Command = 0x63 => "command",
        /// `m`: text messages.
        Message = 0x6D => "message",
        /// `r`: MAV states.
        Report = 0x72 => "report",
        /// `t`: periodic telemetry.
        Telemetry = 0x74 => "telemetry",
        /// `w`: warnings, 8-bit text like messages. Only listed in table 25.
        Warning = 0x77 => "warning",
    }
}
