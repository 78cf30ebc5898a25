//! Discovery status of a Transmit Status frame.

code_enum! {
    /// Discovery status of a Transmit Status (0x8B) frame: the overhead the radio spent
    /// finding the destination.
    pub enum DiscoveryStatus {
        /// 0x00: no discovery overhead.
        NoDiscoveryOverhead = 0x00 => "no_discovery_overhead",
        /// 0x01: address discovery.
        AddressDiscovery = 0x01 => "address_discovery",
        /// 0x02: route discovery.
        RouteDiscovery = 0x02 => "route_discovery",
        /// 0x03: address and route discovery.
        AddressAndRouteDiscovery = 0x03 => "address_and_route_discovery",
        /// 0x40: extended timeout discovery.
        ExtendedTimeoutDiscovery = 0x40 => "extended_timeout_discovery",
    }
}
