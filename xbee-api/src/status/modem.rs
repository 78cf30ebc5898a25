//! Status of a Modem Status frame.

code_enum! {
    /// Status of a Modem Status (0x8A) frame, with Digi's codes. The frame's view is
    /// [`ModemStatusFrame`](crate::ModemStatusFrame), its repr
    /// [`ModemStatusRepr`](crate::ModemStatusRepr).
    ///
    /// Codes 0x80 and above are stack errors ([`ModemStatus::StackError`]); any other code
    /// this crate does not name is [`ModemStatus::Unknown`]. Both keep the byte.
    ///
    /// ```
    /// use xbee_api::ModemStatus;
    /// assert_eq!(ModemStatus::from(0x02), ModemStatus::JoinedNetwork);
    /// assert_eq!(u8::from(ModemStatus::StackError(0x91)), 0x91);
    /// assert_eq!(ModemStatus::from(0x00).name(), Some("hardware_reset"));
    /// assert_eq!(ModemStatus::from(0x91).to_string(), "stack_error(0x91)");
    /// assert_eq!(ModemStatus::from(0x7F).to_string(), "unknown(0x7F)");
    /// ```
    pub enum ModemStatus {
        /// 0x00: hardware reset or power up.
        HardwareReset = 0x00 => "hardware_reset",
        /// 0x01: watchdog timer reset.
        WatchdogReset = 0x01 => "watchdog_reset",
        /// 0x02: joined network (routers and end devices).
        JoinedNetwork = 0x02 => "joined_network",
        /// 0x03: disassociated / left the network.
        Disassociated = 0x03 => "disassociated",
        /// 0x04: synchronisation lost.
        SyncLost = 0x04 => "sync_lost",
        /// 0x05: coordinator realignment.
        CoordinatorRealignment = 0x05 => "coordinator_realignment",
        /// 0x06: coordinator started.
        CoordinatorStarted = 0x06 => "coordinator_started",
        /// 0x07: network security key was updated.
        SecurityKeyUpdated = 0x07 => "security_key_updated",
        /// 0x0B: network woke up.
        NetworkWokeUp = 0x0B => "network_woke_up",
        /// 0x0C: network went to sleep.
        NetworkWentToSleep = 0x0C => "network_went_to_sleep",
        /// 0x0D: voltage supply limit exceeded.
        VoltageLimitExceeded = 0x0D => "voltage_limit_exceeded",
        /// 0x0E: remote manager connected.
        RemoteManagerConnected = 0x0E => "remote_manager_connected",
        /// 0x0F: remote manager disconnected.
        RemoteManagerDisconnected = 0x0F => "remote_manager_disconnected",
        /// 0x11: modem configuration changed while a join was in progress.
        ConfigChangedDuringJoin = 0x11 => "config_changed_during_join",
        /// 0x12: access fault.
        AccessFault = 0x12 => "access_fault",
        /// 0x13: fatal error.
        FatalError = 0x13 => "fatal_error",
        /// 0x32: BLE connect.
        BleConnect = 0x32 => "ble_connect",
        /// 0x33: BLE disconnect.
        BleDisconnect = 0x33 => "ble_disconnect",
        /// 0x34: LTE-M/NB-IoT band mask configuration failed (cellular modules).
        BandmaskConfigurationFailed = 0x34 => "bandmask_configuration_failed",
        /// 0x3B: secure session successfully established.
        SecureSessionEstablished = 0x3B => "secure_session_established",
        /// 0x3C: secure session ended.
        SecureSessionEnded = 0x3C => "secure_session_ended",
        /// 0x3D: secure session authentication failed.
        SecureSessionAuthFailed = 0x3D => "secure_session_auth_failed",
        /// 0x3E: coordinator detected a PAN ID conflict but took no action (`CR` = 0).
        PanIdConflictNoAction = 0x3E => "pan_id_conflict_no_action",
        /// 0x3F: coordinator changed PAN ID due to a conflict.
        PanIdChanged = 0x3F => "pan_id_changed",
        /// 0x40: router PAN ID was changed by the coordinator due to a conflict.
        RouterPanIdChanged = 0x40 => "router_pan_id_changed",
        /// 0x42: network watchdog timeout expired three times.
        NetworkWatchdogExpired = 0x42 => "network_watchdog_expired",
        /// 0x43: joining window opened.
        JoinWindowOpened = 0x43 => "join_window_opened",
        /// 0x44: joining window closed.
        JoinWindowClosed = 0x44 => "join_window_closed",
        /// 0x45: network security key change initiated.
        NetworkKeyChangeInitiated = 0x45 => "network_key_change_initiated",
        ;
        /// 0x80..=0xFF: stack error, with the code.
        StackError(0x80..=0xFF) => "stack_error",
    }
}
