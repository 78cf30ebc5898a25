use super::id_enum;

id_enum! {
    /// Controller identifier (table 28). Bytes 0x00 and 0x04-0xFE are valid on the
    /// wire and decode as `Unknown`; in a controllers command 0xFF is the status
    /// request instead.
    ///
    /// ```
    /// use mcp_core::Controller;
    /// assert_eq!(Controller::from(3), Controller::Mpc);
    /// assert_eq!(Controller::from(9), Controller::Unknown(9));
    /// assert_eq!("altitude".parse::<Controller>(), Ok(Controller::Altitude));
    /// ```
    Controller, "controller" {
        /// Manual control.
        Manual = 0x01 => "manual",
        /// Altitude controller.
        Altitude = 0x02 => "altitude",
        /// Model predictive controller.
        Mpc = 0x03 => "mpc",
    }
}
