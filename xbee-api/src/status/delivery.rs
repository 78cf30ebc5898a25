//! Delivery status of a Transmit Status frame.

code_enum! {
    /// Delivery status of a Transmit Status (0x8B) frame, with Digi's Zigbee codes.
    ///
    /// ```
    /// use xbee_api::DeliveryStatus;
    /// assert_eq!(DeliveryStatus::from(0x25), DeliveryStatus::RouteNotFound);
    /// assert_eq!(u8::from(DeliveryStatus::Unknown(0x99)), 0x99);
    /// assert_eq!(DeliveryStatus::RouteNotFound.name(), Some("route_not_found"));
    /// assert_eq!(DeliveryStatus::RouteNotFound.to_string(), "route_not_found");
    /// assert_eq!(DeliveryStatus::Unknown(0x99).name(), None);
    /// assert_eq!(DeliveryStatus::Unknown(0x99).to_string(), "unknown(0x99)");
    /// ```
    pub enum DeliveryStatus {
        /// 0x00: success.
        Success = 0x00 => "success",
        /// 0x01: MAC ACK failure.
        MacAckFailure = 0x01 => "mac_ack_failure",
        /// 0x02: CCA (clear channel assessment) / LBT failure.
        CcaFailure = 0x02 => "cca_failure",
        /// 0x03: transmission purged: attempted before the stack was up.
        Purged = 0x03 => "purged",
        /// 0x15: invalid destination endpoint.
        InvalidDestinationEndpoint = 0x15 => "invalid_destination_endpoint",
        /// 0x21: network ACK failure.
        NetworkAckFailure = 0x21 => "network_ack_failure",
        /// 0x22: not joined to a network.
        NotJoinedToNetwork = 0x22 => "not_joined_to_network",
        /// 0x23: self-addressed.
        SelfAddressed = 0x23 => "self_addressed",
        /// 0x24: address not found.
        AddressNotFound = 0x24 => "address_not_found",
        /// 0x25: route not found.
        RouteNotFound = 0x25 => "route_not_found",
        /// 0x26: broadcast source failed to hear a neighbour relay the message.
        BroadcastRelayNotHeard = 0x26 => "broadcast_relay_not_heard",
        /// 0x2B: invalid binding table index.
        InvalidBindingTableIndex = 0x2B => "invalid_binding_table_index",
        /// 0x2C: resource error (lack of free buffers, timers...).
        ResourceErrorBuffers = 0x2C => "resource_error_buffers",
        /// 0x2D: attempted broadcast with APS transmission.
        BroadcastWithAps = 0x2D => "broadcast_with_aps",
        /// 0x2E: attempted unicast with APS transmission, but EE = 0.
        UnicastWithApsEe0 = 0x2E => "unicast_with_aps_ee0",
        /// 0x31: internal resource error.
        InternalResourceError = 0x31 => "internal_resource_error",
        /// 0x32: resource error (lack of free buffers, timers...).
        ResourceError = 0x32 => "resource_error",
        /// 0x34: no secure session connection.
        NoSecureSession = 0x34 => "no_secure_session",
        /// 0x35: encryption failure.
        EncryptionFailure = 0x35 => "encryption_failure",
        /// 0x74: data payload too large.
        PayloadTooLarge = 0x74 => "payload_too_large",
        /// 0x75: indirect message unrequested.
        IndirectMessageUnrequested = 0x75 => "indirect_message_unrequested",
    }
}

impl DeliveryStatus {
    /// Whether the frame was delivered.
    pub const fn is_success(self) -> bool {
        matches!(self.normalized(), Self::Success)
    }
}
