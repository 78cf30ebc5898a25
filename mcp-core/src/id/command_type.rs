use super::id_enum;

id_enum! {
    /// Command type, the second byte of a command packet (tables 2 and 26); report
    /// types use the same values (table 17, which has no position set report).
    ///
    /// ```
    /// use mcp_core::CommandType;
    /// assert_eq!(CommandType::from(4), CommandType::TrajectorySet);
    /// assert_eq!(CommandType::TrajectorySet.name(), Some("trajectory_set"));
    /// assert_eq!("0x07".parse::<CommandType>(), Ok(CommandType::PositionSet));
    /// ```
    CommandType, "command type" {
        /// Choose the telemetry sent to the coordinator.
        TelemetryToCoordinator = 0x01 => "telemetry_to_coordinator",
        /// Enable or disable autonomous landing.
        Landing = 0x02 => "landing",
        /// Switch the active controller.
        Controllers = 0x03 => "controllers",
        /// Set trajectory waypoints.
        TrajectorySet = 0x04 => "trajectory_set",
        /// Set the slave MAV for coordinate system distribution.
        PositionSlaveSet = 0x05 => "position_slave_set",
        /// Set the MAV time (POSIX seconds).
        Time = 0x06 => "time",
        /// Set the MAV position in a new coordinate system (commands only).
        PositionSet = 0x07 => "position_set",
    }
}
