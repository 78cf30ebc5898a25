//! Status of a Modem Status frame.

/// Status of a Modem Status (0x8A) frame, with Digi's codes.
///
/// Codes 0x80 and above are stack errors ([`ModemStatus::StackError`]); any other code
/// this crate does not name is [`ModemStatus::Unknown`]. Both keep the byte.
///
/// ```
/// use xbee_api::ModemStatus;
/// assert_eq!(ModemStatus::from(0x02), ModemStatus::JoinedNetwork);
/// assert_eq!(u8::from(ModemStatus::StackError(0x91)), 0x91);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModemStatus {
    /// 0x00: hardware reset or power up.
    HardwareReset,
    /// 0x01: watchdog timer reset.
    WatchdogReset,
    /// 0x02: joined network (routers and end devices).
    JoinedNetwork,
    /// 0x03: disassociated / left the network.
    Disassociated,
    /// 0x04: synchronisation lost.
    SyncLost,
    /// 0x05: coordinator realignment.
    CoordinatorRealignment,
    /// 0x06: coordinator started.
    CoordinatorStarted,
    /// 0x07: network security key was updated.
    SecurityKeyUpdated,
    /// 0x0B: network woke up.
    NetworkWokeUp,
    /// 0x0C: network went to sleep.
    NetworkWentToSleep,
    /// 0x0D: voltage supply limit exceeded.
    VoltageLimitExceeded,
    /// 0x0E: remote manager connected.
    RemoteManagerConnected,
    /// 0x0F: remote manager disconnected.
    RemoteManagerDisconnected,
    /// 0x11: modem configuration changed while a join was in progress.
    ConfigChangedDuringJoin,
    /// 0x12: access fault.
    AccessFault,
    /// 0x13: fatal error.
    FatalError,
    /// 0x32: BLE connect.
    BleConnect,
    /// 0x33: BLE disconnect.
    BleDisconnect,
    /// 0x34: no secure session connection.
    NoSecureSession,
    /// 0x3B: secure session successfully established.
    SecureSessionEstablished,
    /// 0x3C: secure session ended.
    SecureSessionEnded,
    /// 0x3D: secure session authentication failed.
    SecureSessionAuthFailed,
    /// 0x3E: coordinator detected a PAN ID conflict but took no action (`CR` = 0).
    PanIdConflictNoAction,
    /// 0x3F: coordinator changed PAN ID due to a conflict.
    PanIdChanged,
    /// 0x40: router PAN ID was changed by the coordinator due to a conflict.
    RouterPanIdChanged,
    /// 0x42: network watchdog timeout expired three times.
    NetworkWatchdogExpired,
    /// 0x43: joining window opened.
    JoinWindowOpened,
    /// 0x44: joining window closed.
    JoinWindowClosed,
    /// 0x80..=0xFF: stack error, with the code.
    StackError(u8),
    /// Any other code, kept as received.
    Unknown(u8),
}

const NAMED: [(u8, ModemStatus); 28] = [
    (0x00, ModemStatus::HardwareReset),
    (0x01, ModemStatus::WatchdogReset),
    (0x02, ModemStatus::JoinedNetwork),
    (0x03, ModemStatus::Disassociated),
    (0x04, ModemStatus::SyncLost),
    (0x05, ModemStatus::CoordinatorRealignment),
    (0x06, ModemStatus::CoordinatorStarted),
    (0x07, ModemStatus::SecurityKeyUpdated),
    (0x0B, ModemStatus::NetworkWokeUp),
    (0x0C, ModemStatus::NetworkWentToSleep),
    (0x0D, ModemStatus::VoltageLimitExceeded),
    (0x0E, ModemStatus::RemoteManagerConnected),
    (0x0F, ModemStatus::RemoteManagerDisconnected),
    (0x11, ModemStatus::ConfigChangedDuringJoin),
    (0x12, ModemStatus::AccessFault),
    (0x13, ModemStatus::FatalError),
    (0x32, ModemStatus::BleConnect),
    (0x33, ModemStatus::BleDisconnect),
    (0x34, ModemStatus::NoSecureSession),
    (0x3B, ModemStatus::SecureSessionEstablished),
    (0x3C, ModemStatus::SecureSessionEnded),
    (0x3D, ModemStatus::SecureSessionAuthFailed),
    (0x3E, ModemStatus::PanIdConflictNoAction),
    (0x3F, ModemStatus::PanIdChanged),
    (0x40, ModemStatus::RouterPanIdChanged),
    (0x42, ModemStatus::NetworkWatchdogExpired),
    (0x43, ModemStatus::JoinWindowOpened),
    (0x44, ModemStatus::JoinWindowClosed),
];

impl From<u8> for ModemStatus {
    fn from(code: u8) -> Self {
        if code >= 0x80 {
            return Self::StackError(code);
        }
        NAMED
            .iter()
            .find(|(c, _)| *c == code)
            .map_or(Self::Unknown(code), |(_, status)| *status)
    }
}

impl From<ModemStatus> for u8 {
    fn from(status: ModemStatus) -> u8 {
        match status {
            ModemStatus::StackError(code) | ModemStatus::Unknown(code) => code,
            named => NAMED
                .iter()
                .find(|(_, s)| *s == named)
                .map_or(0, |(c, _)| *c),
        }
    }
}
