//! Delivery status of a Transmit Status frame.

code_enum! {
    /// Delivery status of a Transmit Status (0x8B) frame, with Digi's Zigbee codes.
    ///
    /// ```
    /// use xbee_api::DeliveryStatus;
    /// assert_eq!(DeliveryStatus::from(0x25), DeliveryStatus::RouteNotFound);
    /// assert_eq!(u8::from(DeliveryStatus::Unknown(0x99)), 0x99);
    /// ```
    pub enum DeliveryStatus {
        /// 0x00: success.
        Success = 0x00,
        /// 0x01: MAC ACK failure.
        MacAckFailure = 0x01,
        /// 0x02: CCA (clear channel assessment) / LBT failure.
        CcaFailure = 0x02,
        /// 0x03: transmission purged: attempted before the stack was up.
        Purged = 0x03,
        /// 0x15: invalid destination endpoint.
        InvalidDestinationEndpoint = 0x15,
        /// 0x21: network ACK failure.
        NetworkAckFailure = 0x21,
        /// 0x22: not joined to a network.
        NotJoinedToNetwork = 0x22,
        /// 0x23: self-addressed.
        SelfAddressed = 0x23,
        /// 0x24: address not found.
        AddressNotFound = 0x24,
        /// 0x25: route not found.
        RouteNotFound = 0x25,
        /// 0x26: broadcast source failed to hear a neighbour relay the message.
        BroadcastRelayNotHeard = 0x26,
        /// 0x2B: invalid binding table index.
        InvalidBindingTableIndex = 0x2B,
        /// 0x2C: resource error (lack of free buffers, timers...).
        ResourceErrorBuffers = 0x2C,
        /// 0x2D: attempted broadcast with APS transmission.
        BroadcastWithAps = 0x2D,
        /// 0x2E: attempted unicast with APS transmission, but EE = 0.
        UnicastWithApsEe0 = 0x2E,
        /// 0x31: internal resource error.
        InternalResourceError = 0x31,
        /// 0x32: resource error (lack of free buffers, timers...).
        ResourceError = 0x32,
        /// 0x34: no secure session connection.
        NoSecureSession = 0x34,
        /// 0x35: encryption failure.
        EncryptionFailure = 0x35,
        /// 0x74: data payload too large.
        PayloadTooLarge = 0x74,
        /// 0x75: indirect message unrequested.
        IndirectMessageUnrequested = 0x75,
    }
}

impl DeliveryStatus {
    /// Whether the frame was delivered.
    pub const fn is_success(self) -> bool {
        matches!(self, Self::Success)
    }
}
