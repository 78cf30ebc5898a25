use super::id_enum;

id_enum! {
    /// Telemetry identifier (table 29). The protocol allows 256 ids; 0x21-0xFF are
    /// valid on the wire and decode as `Unknown`. A set of them (the ids enabled for
    /// telemetry, say) is a [`TelemetrySet`](crate::TelemetrySet).
    ///
    /// Each value is an `f32`; the protocol names the quantities but gives no units
    /// (the MAV's firmware decides them), so none are stated here either.
    ///
    /// ```
    /// use mcp_core::TelemetryId;
    /// assert_eq!(TelemetryId::from(0x11), TelemetryId::ValidBlob);
    /// assert_eq!(TelemetryId::ALL.len(), 33);
    /// assert_eq!(
    ///     "aileron_acceleration_error".parse::<TelemetryId>(),
    ///     Ok(TelemetryId::AileronAccelerationError)
    /// );
    /// assert_eq!(TelemetryId::from(0x21).to_string(), "unknown(0x21)");
    /// ```
    TelemetryId, "telemetry id" {
        /// Estimated altitude.
        EstimatedAltitude = 0x00 => "estimated_altitude",
        /// Altitude.
        Altitude = 0x01 => "altitude",
        /// Elevator speed.
        ElevatorSpeed = 0x02 => "elevator_speed",
        /// Aileron speed.
        AileronSpeed = 0x03 => "aileron_speed",
        /// Estimated elevator speed.
        EstimatedElevatorSpeed = 0x04 => "estimated_elevator_speed",
        /// Estimated aileron speed.
        EstimatedAileronSpeed = 0x05 => "estimated_aileron_speed",
        /// Elevator position.
        ElevatorPosition = 0x06 => "elevator_position",
        /// Aileron position.
        AileronPosition = 0x07 => "aileron_position",
        /// Altitude controller output.
        AltitudeControllerOutput = 0x08 => "altitude_controller_output",
        /// Altitude speed.
        AltitudeSpeed = 0x09 => "altitude_speed",
        /// Aileron controller output.
        AileronControllerOutput = 0x0A => "aileron_controller_output",
        /// Elevator controller output.
        ElevatorControllerOutput = 0x0B => "elevator_controller_output",
        /// Altitude setpoint.
        AltitudeSetpoint = 0x0C => "altitude_setpoint",
        /// Elevator position setpoint.
        ElevatorPositionSetpoint = 0x0D => "elevator_position_setpoint",
        /// Aileron position setpoint.
        AileronPositionSetpoint = 0x0E => "aileron_position_setpoint",
        /// Elevator acceleration.
        ElevatorAcceleration = 0x0F => "elevator_acceleration",
        /// Aileron acceleration.
        AileronAcceleration = 0x10 => "aileron_acceleration",
        /// Valid blob.
        ValidBlob = 0x11 => "valid_blob",
        /// Output throttle.
        OutputThrottle = 0x12 => "output_throttle",
        /// Output elevator.
        OutputElevator = 0x13 => "output_elevator",
        /// Output aileron.
        OutputAileron = 0x14 => "output_aileron",
        /// Output rudder.
        OutputRudder = 0x15 => "output_rudder",
        /// Blob elevator.
        BlobElevator = 0x16 => "blob_elevator",
        /// Blob aileron.
        BlobAileron = 0x17 => "blob_aileron",
        /// Blob altitude.
        BlobAltitude = 0x18 => "blob_altitude",
        /// Pitch angle.
        PitchAngle = 0x19 => "pitch_angle",
        /// Roll angle.
        RollAngle = 0x1A => "roll_angle",
        /// Elevator shift.
        ElevatorShift = 0x1B => "elevator_shift",
        /// Aileron shift.
        AileronShift = 0x1C => "aileron_shift",
        /// Elevator acceleration input.
        ElevatorAccelerationInput = 0x1D => "elevator_acceleration_input",
        /// Elevator acceleration error.
        ElevatorAccelerationError = 0x1E => "elevator_acceleration_error",
        /// Aileron acceleration input.
        AileronAccelerationInput = 0x1F => "aileron_acceleration_input",
        /// Aileron acceleration error.
        AileronAccelerationError = 0x20 => "aileron_acceleration_error",
    }
}
