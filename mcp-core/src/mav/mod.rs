//! The MAV side: a state machine that answers commands the way the deployed MAV does.
//!
//! [`Mav`] holds the protocol state (which telemetry ids are enabled, the four slave
//! addresses, the last landing state and controller it reported); everything else goes
//! through the [`Vehicle`] trait, which the firmware or a simulator implements. Answers
//! are written into caller buffers; nothing allocates. Each answer goes back as the RF
//! data of a Transmit Request to the coordinator (the ground station's radio), whichever
//! node the command came from, frame id 0 and transmit options 0x01,
//! as the deployed MAV sends them (with `xbee-api`: `TransmitRequestRepr { options:
//! transmit_options::DISABLE_RETRIES,
//! ..TransmitRequestRepr::unicast(Address64::COORDINATOR, reply) }`, encoded or built in
//! place); the commands come from the RF data of the Receive Packets the radio hands
//! over (`ReceivePacket::new_checked(frame.data())?.data()`). A MAV acts on commands
//! alone: parsed with [`Command::parse`](crate::Command::parse) and given to
//! [`Mav::handle`], they take less flash than [`parse`](crate::parse) and
//! [`Mav::handle_packet`], which link the parsers of every category (600 bytes less in
//! the repository's Cortex-M3 firmware example).
//!
//! Behaviour:
//!
//! - [`Mav::handle`] answers a status request with the matching report, and a trajectory
//!   set with a trajectory report at once. Other set commands get no reply.
//! - A landing state or controller change produces that report unsolicited:
//!   [`Mav::poll_changes`] compares the vehicle's state with the last one it reported
//!   (unsolicited, or in answer to a status request).
//!   Call it after every command and in the main loop (the vehicle may change state on
//!   its own, e.g. when a landing ends), until it returns `None`.
//! - [`Mav::telemetry`] builds the 20 Hz telemetry packet: every enabled id in
//!   ascending order, nothing when none is enabled. 50 records fill the 255-byte
//!   payload (16 an 84-byte one): the ids past those go in the next packets, each
//!   starting where the last one stopped, so that every enabled id is sent, less often.
//! - Position slave set: the MAV keeps the firmware's four slots. A spec-form command
//!   (no slot) sets slot 0. The status request is answered with the firmware-form
//!   report (four addresses, 34 bytes), as the deployed MAV answers it; a MAV built
//!   [`with_spec_slave_report`](Mav::with_spec_slave_report) answers with the spec's
//!   (table 22: slot 0's address, 10 bytes), for ground stations that know only the
//!   spec's form.
//! - Telemetry to coordinator accepts every id 0-255; ids outside table 29 are enabled
//!   like the others and read through [`Vehicle::telemetry`].
//!
//! ```
//! use mcp_core::mav::{Mav, Vehicle};
//! use mcp_core::{parse, Packet, Controller, LandingState, TelemetryId};
//!
//! struct Sim { landing: LandingState, controller: Controller, time: u32 }
//!
//! // No position control and no trajectory: the methods for those keep their defaults.
//! impl Vehicle for Sim {
//!     fn landing_state(&self) -> LandingState { self.landing }
//!     fn set_landing(&mut self, on: bool) {
//!         self.landing = if on { LandingState::Landing } else { LandingState::Flight };
//!     }
//!     fn controller(&self) -> Controller { self.controller }
//!     fn set_controller(&mut self, c: Controller) { self.controller = c }
//!     fn time(&self) -> u32 { self.time }
//!     fn set_time(&mut self, t: u32) { self.time = t }
//!     fn telemetry(&self, _id: TelemetryId) -> f32 { 0.0 }
//! }
//!
//! let mut sim = Sim { landing: LandingState::Flight, controller: Controller::Manual, time: 0 };
//! let mut mav = Mav::new(&sim);
//! // Room for any reply: a trajectory report of 15 waypoints takes 243 bytes. A firmware
//! // whose Transmit Requests take `MAX_UNFRAGMENTED_PAYLOAD` (84) bytes gives it that,
//! // and a trajectory report then holds the first 5 waypoints (as many as fit). The
//! // telemetry buffer is best kept to `MAX_UNFRAGMENTED_PAYLOAD` (see `Mav::telemetry`).
//! let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
//!
//! // Landing on: no direct reply, then the unsolicited landing report.
//! let Ok(Packet::Command(cmd)) = parse(b"c\x02\x01") else { panic!() };
//! assert_eq!(mav.handle(&mut sim, &cmd, &mut buf), Ok(None));
//! let len = mav.poll_changes(&sim, &mut buf).unwrap().unwrap();
//! assert_eq!(&buf[..len], b"r\x02\x01");
//! assert_eq!(mav.poll_changes(&sim, &mut buf), Ok(None));
//!
//! // A status request gets the matching report.
//! let Ok(Packet::Command(cmd)) = parse(b"c\x03\xff") else { panic!() };
//! let len = mav.handle(&mut sim, &cmd, &mut buf).unwrap().unwrap();
//! assert_eq!(&buf[..len], b"r\x03\x01");
//! ```
//!
//! A length returned is never more than `buf.len()`, but the compiler cannot always see
//! that across the call: in firmware that must link no panic path, take the reply with
//! `buf.get(..len)` rather than `&buf[..len]`, whose bounds check stays.

mod telemetry_set;
mod vehicle;

pub use telemetry_set::{TelemetrySet, TelemetrySetIter};
pub use vehicle::Vehicle;

use crate::{
    Address, BufferTooSmall, Command, Packet, Report, SlaveAddresses, StatusRequest,
    TelemetryBuilder, TrajectoryBuilder, field,
    id::{Controller, LandingState},
};

/// The MAV's protocol state machine. See the [module docs](self).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mav {
    enabled: TelemetrySet,
    slaves: [Address; 4],
    spec_slave_report: bool,
    landing: LandingState,
    controller: Controller,
    /// The id the next telemetry packet starts from: past 0 while the enabled ids take
    /// more than one packet, the first the last packet left out.
    telemetry_from: u8,
}

impl Mav {
    /// A MAV with no telemetry enabled and all slave addresses zero, taking the
    /// vehicle's current landing state and controller as already reported.
    pub fn new<V: Vehicle + ?Sized>(vehicle: &V) -> Self {
        Self::with_state(vehicle.landing_state(), vehicle.controller())
    }

    /// [`Mav::new`] from the landing state and controller themselves, in a `const`
    /// context: for a `Mav` in a `static` that an interrupt handler shares.
    ///
    /// ```
    /// use core::cell::RefCell;
    /// use mcp_core::mav::Mav;
    /// use mcp_core::{Controller, LandingState};
    ///
    /// // With a critical-section mutex around it on a microcontroller.
    /// static MAV: std::sync::Mutex<RefCell<Mav>> = std::sync::Mutex::new(RefCell::new(
    ///     Mav::with_state(LandingState::OnGround, Controller::Manual),
    /// ));
    /// assert!(MAV.lock().unwrap().borrow().enabled().is_empty());
    /// ```
    pub const fn with_state(landing: LandingState, controller: Controller) -> Self {
        Mav {
            enabled: TelemetrySet::new(),
            slaves: [Address([0; 8]); 4],
            spec_slave_report: false,
            telemetry_from: 0,
            landing,
            controller,
        }
    }

    /// The MAV with `enabled` as the telemetry ids sent to the coordinator, in a `const`
    /// context: a `static` MAV that sends telemetry from start-up.
    ///
    /// ```
    /// use mcp_core::mav::{Mav, TelemetrySet};
    /// use mcp_core::{Controller, LandingState, TelemetryId};
    ///
    /// const MAV: Mav = Mav::with_state(LandingState::OnGround, Controller::Manual)
    ///     .with_enabled(TelemetrySet::new().with(TelemetryId::Altitude));
    /// assert!(MAV.enabled().contains(TelemetryId::Altitude));
    /// ```
    #[must_use]
    pub const fn with_enabled(mut self, enabled: TelemetrySet) -> Self {
        self.enabled = enabled;
        self
    }

    /// The MAV answering the position slave set status request in the spec's form
    /// (table 22: `r 05` and the address of slot 0, 10 bytes) instead of the deployed
    /// firmware's (the four slots' addresses, 34 bytes): for a ground station that knows
    /// only the spec's form.
    ///
    /// ```
    /// use mcp_core::mav::Mav;
    /// use mcp_core::{Command, Controller, LandingState, StatusRequest};
    /// # use mcp_core::{TelemetryId, mav::Vehicle};
    /// # struct Sim;
    /// # impl Vehicle for Sim {
    /// #     fn landing_state(&self) -> LandingState { LandingState::OnGround }
    /// #     fn set_landing(&mut self, _on: bool) {}
    /// #     fn controller(&self) -> Controller { Controller::Manual }
    /// #     fn set_controller(&mut self, _c: Controller) {}
    /// #     fn time(&self) -> u32 { 0 }
    /// #     fn set_time(&mut self, _t: u32) {}
    /// #     fn telemetry(&self, _id: TelemetryId) -> f32 { 0.0 }
    /// # }
    /// # let mut sim = Sim;
    /// let mut mav = Mav::with_state(LandingState::OnGround, Controller::Manual)
    ///     .with_spec_slave_report();
    /// let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    /// let request = Command::<&[u8]>::StatusRequest(StatusRequest::PositionSlaveSet);
    /// let len = mav.handle(&mut sim, &request, &mut buf)?.unwrap();
    /// assert_eq!(&buf[..len], b"r\x05\0\0\0\0\0\0\0\0");
    /// # Ok::<(), mcp_core::BufferTooSmall>(())
    /// ```
    #[must_use]
    pub const fn with_spec_slave_report(mut self) -> Self {
        self.spec_slave_report = true;
        self
    }

    /// The telemetry ids sent to the coordinator.
    pub fn enabled(&self) -> &TelemetrySet {
        &self.enabled
    }

    /// The telemetry ids sent to the coordinator, to change them directly.
    pub fn enabled_mut(&mut self) -> &mut TelemetrySet {
        &mut self.enabled
    }

    /// The slave addresses of slots 0 to 3.
    pub fn slaves(&self) -> [Address; 4] {
        self.slaves
    }

    /// Carries out a command and writes the direct reply, if any, into `buf`,
    /// returning its length. Status requests get the matching report; trajectory set
    /// gets a trajectory report (as many of the vehicle's waypoints as fit); other
    /// set commands get none. On error (`buf` too small for the reply) the command
    /// has still been carried out.
    ///
    /// Call [`Mav::poll_changes`] afterwards for the unsolicited reports.
    pub fn handle<V, B>(
        &mut self,
        vehicle: &mut V,
        command: &Command<B>,
        buf: &mut [u8],
    ) -> Result<Option<usize>, BufferTooSmall>
    where
        V: Vehicle + ?Sized,
        B: AsRef<[u8]>,
    {
        match command {
            Command::TelemetryToCoordinator { on, id } => {
                self.enabled.set(*id, *on);
                Ok(None)
            }
            Command::Landing { on } => {
                vehicle.set_landing(*on);
                Ok(None)
            }
            Command::Controllers(c) => {
                vehicle.set_controller(*c);
                Ok(None)
            }
            Command::TrajectorySet(waypoints) => {
                vehicle.set_trajectory(waypoints.as_borrowed());
                Self::trajectory_report(vehicle, buf).map(Some)
            }
            Command::PositionSlaveSet { slot, address } => {
                let slot = slot.unwrap_or_default();
                if let Some(s) = self.slaves.get_mut(slot.index()) {
                    *s = *address;
                }
                vehicle.set_slave(slot, *address);
                Ok(None)
            }
            Command::Time(time) => {
                vehicle.set_time(*time);
                Ok(None)
            }
            Command::PositionSet { elevator, aileron } => {
                vehicle.set_position(*elevator, *aileron);
                Ok(None)
            }
            Command::StatusRequest(request) => self.answer(vehicle, *request, buf).map(Some),
        }
    }

    /// Like [`Mav::handle`] for any packet: commands are handled, other categories
    /// (telemetry, reports, messages, warnings) are ignored.
    pub fn handle_packet<V, B>(
        &mut self,
        vehicle: &mut V,
        packet: &Packet<B>,
        buf: &mut [u8],
    ) -> Result<Option<usize>, BufferTooSmall>
    where
        V: Vehicle + ?Sized,
        B: AsRef<[u8]>,
    {
        match packet {
            Packet::Command(command) => self.handle(vehicle, command, buf),
            _ => Ok(None),
        }
    }

    /// Writes the report answering a status request. A landing state or controller
    /// answered counts as reported: [`poll_changes`](Self::poll_changes) does not
    /// report it again.
    fn answer<V: Vehicle + ?Sized>(
        &mut self,
        vehicle: &V,
        request: StatusRequest,
        buf: &mut [u8],
    ) -> Result<usize, BufferTooSmall> {
        let report: Report<&[u8]> = match request {
            StatusRequest::TelemetryToCoordinator(id) => Report::TelemetryToCoordinator {
                on: self.enabled.contains(id),
                id,
            },
            StatusRequest::Landing => Report::Landing(vehicle.landing_state()),
            StatusRequest::Controllers => Report::Controllers(vehicle.controller()),
            StatusRequest::TrajectorySet => return Self::trajectory_report(vehicle, buf),
            StatusRequest::PositionSlaveSet if self.spec_slave_report => {
                Report::PositionSlaveSet(SlaveAddresses::Single(self.slaves[0]))
            }
            StatusRequest::PositionSlaveSet => {
                Report::PositionSlaveSet(SlaveAddresses::Slots(self.slaves))
            }
            StatusRequest::Time => Report::Time(vehicle.time()),
        };
        let len = report.encode(buf)?;
        match report {
            Report::Landing(state) => self.landing = state,
            Report::Controllers(controller) => self.controller = controller,
            _ => {}
        }
        Ok(len)
    }

    /// Writes a trajectory report of the vehicle's waypoints, as many as fit.
    fn trajectory_report<V: Vehicle + ?Sized>(
        vehicle: &V,
        buf: &mut [u8],
    ) -> Result<usize, BufferTooSmall> {
        let mut builder = TrajectoryBuilder::report(buf)?;
        let mut index = 0;
        while let Some(waypoint) = vehicle.waypoint(index) {
            if builder.push(waypoint).is_err() {
                break;
            }
            index += 1;
        }
        Ok(builder.finish())
    }

    /// Writes one unsolicited report if the vehicle's landing state or controller
    /// changed since the last one reported (landing first), returning its length.
    /// Returns `None` when nothing changed; call again until it does, as both may
    /// have changed. If `buf` is too small, the change stays pending.
    pub fn poll_changes<V: Vehicle + ?Sized>(
        &mut self,
        vehicle: &V,
        buf: &mut [u8],
    ) -> Result<Option<usize>, BufferTooSmall> {
        let landing = vehicle.landing_state();
        if landing != self.landing {
            let len = Report::<&[u8]>::Landing(landing).encode(buf)?;
            self.landing = landing;
            return Ok(Some(len));
        }
        let controller = vehicle.controller();
        if controller != self.controller {
            let len = Report::<&[u8]>::Controllers(controller).encode(buf)?;
            self.controller = controller;
            return Ok(Some(len));
        }
        Ok(None)
    }

    /// Writes the periodic telemetry packet: every enabled id in ascending order with
    /// its value from [`Vehicle::telemetry`]. Returns `None` (send nothing) when no id
    /// is enabled. If not even one record fits `buf`, the error (a packet with no
    /// record would say that none is enabled), which needs room for one record, 6
    /// bytes.
    ///
    /// When the enabled ids take more records than fit `buf` (or the 255-byte payload),
    /// the packet holds the first ones, and the next packet goes on from the first id
    /// left out, up to the highest enabled id; the one after starts from the lowest
    /// again. Each packet is in ascending order, and every enabled id is sent (the
    /// status report that says an id is on never lies): with `k` packets to a round,
    /// each id once every `k` periods.
    ///
    /// `buf` sets how many records a packet takes: each is 5 bytes after a 1-byte
    /// header. A buffer of [`MAX_PAYLOAD`](crate::MAX_PAYLOAD) takes 50, in a packet of
    /// up to 251 bytes, which a Zigbee XBee carries only in fragments; one of
    /// [`MAX_UNFRAGMENTED_PAYLOAD`](crate::MAX_UNFRAGMENTED_PAYLOAD) (84 bytes) takes
    /// 16, in one radio packet.
    ///
    /// ```
    /// # use mcp_core::mav::{Mav, Vehicle};
    /// # use mcp_core::{Controller, LandingState, TelemetryId};
    /// # struct Sim;
    /// # impl Vehicle for Sim {
    /// #     fn landing_state(&self) -> LandingState { LandingState::Flight }
    /// #     fn set_landing(&mut self, _on: bool) {}
    /// #     fn controller(&self) -> Controller { Controller::Manual }
    /// #     fn set_controller(&mut self, _c: Controller) {}
    /// #     fn time(&self) -> u32 { 0 }
    /// #     fn set_time(&mut self, _t: u32) {}
    /// #     fn telemetry(&self, _id: TelemetryId) -> f32 { 1.5 }
    /// # }
    /// let mut mav = Mav::with_state(LandingState::Flight, Controller::Manual);
    /// for id in 1..=20 {
    ///     mav.enabled_mut().insert(TelemetryId::from(id));
    /// }
    /// // One radio packet: the first 16 ids of the 20, then the 4 left, then again.
    /// let mut buf = [0u8; 84];
    /// assert_eq!(mav.telemetry(&Sim, &mut buf), Ok(Some(1 + 16 * 5)));
    /// assert_eq!(buf[1], 1);
    /// assert_eq!(mav.telemetry(&Sim, &mut buf), Ok(Some(1 + 4 * 5)));
    /// assert_eq!(buf[1], 17);
    /// assert_eq!(mav.telemetry(&Sim, &mut buf), Ok(Some(1 + 16 * 5)));
    /// assert_eq!(buf[1], 1);
    /// // No room for a record.
    /// for len in [0, 5] {
    ///     let error = mav.telemetry(&Sim, &mut buf[..len]).unwrap_err();
    ///     assert_eq!((error.needed, error.available), (6, len));
    /// }
    /// ```
    pub fn telemetry<V: Vehicle + ?Sized>(
        &mut self,
        vehicle: &V,
        buf: &mut [u8],
    ) -> Result<Option<usize>, BufferTooSmall> {
        if self.enabled.is_empty() {
            return Ok(None);
        }
        let too_small = BufferTooSmall {
            needed: field::RECORDS + field::record::LEN,
            available: buf.len(),
        };
        let mut builder = TelemetryBuilder::new(buf).map_err(|_| too_small)?;
        let mut from = self.telemetry_from;
        let mut left_out = 0;
        loop {
            for id in self.enabled.iter_from(from) {
                if builder.push(id, vehicle.telemetry(id)).is_err() {
                    left_out = u8::from(id);
                    break;
                }
            }
            // None left from `from` on (disabled meanwhile): from the lowest again.
            if builder.count() > 0 || from == 0 {
                break;
            }
            from = 0;
        }
        if builder.count() == 0 {
            return Err(too_small);
        }
        self.telemetry_from = left_out;
        Ok(Some(builder.finish()))
    }
}
