//! Whether a MAV took a set command: the status request to ask, and the reports that
//! say yes.
//!
//! MCP set commands get no reply (but trajectory set, answered at once by a trajectory
//! report): a ground station that must know a command was carried out asks the
//! matching status request and compares the report with what it set.

use crate::{
    address::Slot,
    command::{Command, StatusRequest},
    id::LandingState,
    report::{Report, SlaveAddresses},
    trajectory::Waypoints,
};

/// How far past the time set a MAV's time report may be and still confirm a time
/// command, in seconds: the MAV's clock runs on from the time set while the request
/// and its report are on their way (a few seconds over a radio with retries).
pub const TIME_CONFIRM_WINDOW: u32 = 60;

impl<B: AsRef<[u8]>> Command<B> {
    /// The status request whose report says whether a MAV took this command: the
    /// request of the same type (for telemetry to coordinator, on the same telemetry
    /// id). `None` for position set, which has no status request, and for a status
    /// request itself.
    ///
    /// ```
    /// use mcp_core::{Command, StatusRequest, TelemetryId};
    ///
    /// assert_eq!(Command::landing(true).confirming_request(), Some(StatusRequest::Landing));
    /// assert_eq!(
    ///     Command::telemetry_to_coordinator(true, TelemetryId::Altitude).confirming_request(),
    ///     Some(StatusRequest::TelemetryToCoordinator(TelemetryId::Altitude))
    /// );
    /// assert_eq!(Command::position_set(0.5, 0.0).confirming_request(), None);
    /// ```
    pub fn confirming_request(&self) -> Option<StatusRequest> {
        Some(match self {
            Command::TelemetryToCoordinator { id, .. } => {
                StatusRequest::TelemetryToCoordinator(*id)
            }
            Command::Landing { .. } => StatusRequest::Landing,
            Command::Controllers(_) => StatusRequest::Controllers,
            Command::TrajectorySet(_) => StatusRequest::TrajectorySet,
            Command::PositionSlaveSet { .. } => StatusRequest::PositionSlaveSet,
            Command::Time(_) => StatusRequest::Time,
            Command::PositionSet { .. } | Command::StatusRequest(_) => return None,
        })
    }

    /// Whether `report` shows this command carried out ([`Command::confirmation`]
    /// is [`Confirmation::Taken`]).
    ///
    /// ```
    /// use mcp_core::{Command, Controller, LandingState, Report};
    ///
    /// let land = Command::landing(true);
    /// assert!(land.is_confirmed_by(&Report::landing(LandingState::Landing)));
    /// assert!(land.is_confirmed_by(&Report::landing(LandingState::OnGround)));
    /// assert!(!land.is_confirmed_by(&Report::landing(LandingState::Flight)));
    ///
    /// let mpc = Command::controllers(Controller::Mpc);
    /// assert!(mpc.is_confirmed_by(&Report::controllers(Controller::Mpc)));
    /// assert!(!mpc.is_confirmed_by(&Report::controllers(Controller::Manual)));
    ///
    /// let time = Command::time(1_700_000_000);
    /// assert!(time.is_confirmed_by(&Report::time(1_700_000_002)));
    /// assert!(!time.is_confirmed_by(&Report::time(1_699_999_999)));
    /// ```
    pub fn is_confirmed_by<R: AsRef<[u8]>>(&self, report: &Report<R>) -> bool {
        self.confirmation(report) == Confirmation::Taken
    }

    /// What `report`, the answer to this command's
    /// [`confirming_request`](Self::confirming_request), says of it:
    ///
    /// - telemetry to coordinator: the same telemetry id, sent or not as commanded;
    /// - landing on: taken when the MAV is landing or on the ground, not taken when it
    ///   is taking off, stabilizing or in flight; landing off: not taken when it is
    ///   landing, taken in any other state of table 27 (the protocol does not say
    ///   whether a MAV on the ground takes off);
    /// - controllers: the controller commanded is active;
    /// - trajectory set: the same waypoints, bit for bit (a MAV that kept fewer did not
    ///   take it);
    /// - position slave set: the address is in the slot set (slot 0 for the spec
    ///   form); a spec-form report holds slot 0 alone, so it cannot say of another
    ///   slot ([`Confirmation::Unknown`]);
    /// - time: the MAV's time is the time set, or up to [`TIME_CONFIRM_WINDOW`] seconds
    ///   past it (a ground station that knows when it sent the command holds the report
    ///   to the seconds since, as `mcp-host` does);
    /// - a report of another type, a landing state outside table 27, and any report for
    ///   a position set or a status request: [`Confirmation::Unknown`].
    ///
    /// ```
    /// use mcp_core::{Address, Command, Confirmation, Report, SlaveAddresses, Slot};
    ///
    /// let slave = Address::from_u64(0x0013_A200_40B5_99BF);
    /// let set = Command::position_slave_set(Slot::new(2), slave);
    /// let spec_form = Report::position_slave_set(SlaveAddresses::Single(slave));
    /// assert_eq!(set.confirmation(&spec_form), Confirmation::Unknown);
    /// let firmware_form = Report::position_slave_set(SlaveAddresses::Slots([slave; 4]));
    /// assert_eq!(set.confirmation(&firmware_form), Confirmation::Taken);
    /// ```
    pub fn confirmation<R: AsRef<[u8]>>(&self, report: &Report<R>) -> Confirmation {
        use Confirmation::{NotTaken, Taken, Unknown};
        let taken = |yes: bool| if yes { Taken } else { NotTaken };
        match (self, report) {
            (
                Command::TelemetryToCoordinator { on, id },
                Report::TelemetryToCoordinator {
                    on: sent,
                    id: reported,
                },
            ) => taken(on == sent && id == reported),
            (Command::Landing { .. }, Report::Landing(LandingState::Unknown(_))) => Unknown,
            (Command::Landing { on: true }, Report::Landing(state)) => taken(matches!(
                state,
                LandingState::Landing | LandingState::OnGround
            )),
            (Command::Landing { on: false }, Report::Landing(state)) => {
                taken(*state != LandingState::Landing)
            }
            (Command::Controllers(set), Report::Controllers(active)) => taken(set == active),
            (Command::TrajectorySet(set), Report::TrajectorySet(reported)) => {
                taken(same_waypoints(set, reported))
            }
            (Command::PositionSlaveSet { slot, address }, Report::PositionSlaveSet(slaves)) => {
                let slot = slot.unwrap_or_default();
                match slaves {
                    SlaveAddresses::Single(first) if slot == Slot::default() => {
                        taken(first == address)
                    }
                    SlaveAddresses::Single(_) => Unknown,
                    SlaveAddresses::Slots(slots) => taken(slots.get(slot.index()) == Some(address)),
                }
            }
            (Command::Time(set), Report::Time(time)) => taken(
                time.checked_sub(*set)
                    .is_some_and(|past| past <= TIME_CONFIRM_WINDOW),
            ),
            _ => Unknown,
        }
    }
}

/// What a MAV's report says of a set command: [`Command::confirmation`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Confirmation {
    /// The report shows the command carried out.
    Taken,
    /// The report shows another state: the MAV did not take the command (an unknown
    /// controller, fewer waypoints than sent), or something changed it since.
    NotTaken,
    /// The report cannot say: a spec-form slave report of a command for slot 1-3, a
    /// landing state outside table 27, a report of another type.
    Unknown,
}

/// Whether two trajectories hold the same waypoints, bit for bit.
fn same_waypoints<A: AsRef<[u8]>, B: AsRef<[u8]>>(a: &Waypoints<A>, b: &Waypoints<B>) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b.iter())
            .all(|(a, b)| a.to_bytes() == b.to_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Address, Controller, TelemetryId, TrajectoryBuilder, Waypoint};

    #[test]
    fn landing_on_is_taken_when_landing_or_on_the_ground_and_off_when_not_landing() {
        use Confirmation::*;
        use LandingState::*;
        for (state, on, off) in [
            (OnGround, Taken, Taken),
            (Landing, Taken, NotTaken),
            (Stabilization, NotTaken, Taken),
            (TakeOff, NotTaken, Taken),
            (Flight, NotTaken, Taken),
            (
                LandingState::Unknown(0x05),
                Confirmation::Unknown,
                Confirmation::Unknown,
            ),
        ] {
            let report = Report::landing(state);
            assert_eq!(
                Command::landing(true).confirmation(&report),
                on,
                "{state:?}"
            );
            assert_eq!(
                Command::landing(false).confirmation(&report),
                off,
                "{state:?}"
            );
        }
    }

    #[test]
    fn telemetry_is_confirmed_by_its_own_id_in_the_state_commanded() {
        let on = Command::telemetry_to_coordinator(true, TelemetryId::Altitude);
        assert!(on.is_confirmed_by(&Report::telemetry_to_coordinator(
            true,
            TelemetryId::Altitude
        )));
        assert!(!on.is_confirmed_by(&Report::telemetry_to_coordinator(
            false,
            TelemetryId::Altitude
        )));
        assert!(!on.is_confirmed_by(&Report::telemetry_to_coordinator(
            true,
            TelemetryId::EstimatedAltitude
        )));
        let off = Command::telemetry_to_coordinator(false, TelemetryId::Altitude);
        assert!(off.is_confirmed_by(&Report::telemetry_to_coordinator(
            false,
            TelemetryId::Altitude
        )));
    }

    #[test]
    fn a_report_of_another_type_never_confirms() {
        let reports = [
            Report::landing(LandingState::Landing),
            Report::controllers(Controller::Mpc),
            Report::time(5),
            Report::telemetry_to_coordinator(true, TelemetryId::Altitude),
            Report::position_slave_set(SlaveAddresses::Single(Address::from_u64(5))),
        ];
        let commands = [
            Command::landing(true),
            Command::controllers(Controller::Mpc),
            Command::time(5),
            Command::telemetry_to_coordinator(true, TelemetryId::Altitude),
            Command::position_slave_set(None, Address::from_u64(5)),
        ];
        for (i, command) in commands.iter().enumerate() {
            for (j, report) in reports.iter().enumerate() {
                assert_eq!(
                    command.is_confirmed_by(report),
                    i == j,
                    "{command:?} {report:?}"
                );
            }
        }
        // Another type cannot say.
        assert_eq!(commands[0].confirmation(&reports[1]), Confirmation::Unknown);
        // Nothing confirms a position set or a status request.
        for report in reports {
            assert!(!Command::position_set(0.5, 0.5).is_confirmed_by(&report));
            assert!(!Command::status_request(StatusRequest::Landing).is_confirmed_by(&report));
        }
    }

    #[test]
    fn a_slave_address_is_confirmed_in_its_slot_of_either_report_form() {
        let (a, b) = (
            Address::from_u64(0x0013_A200_40B5_99BF),
            Address::from_u64(7),
        );
        let slot2 = Slot::new(2).unwrap();
        let slots = Report::position_slave_set(SlaveAddresses::Slots([b, b, a, b]));
        assert!(Command::position_slave_set(Some(slot2), a).is_confirmed_by(&slots));
        assert!(!Command::position_slave_set(Some(slot2), b).is_confirmed_by(&slots));
        // The spec form sets slot 0.
        assert!(!Command::position_slave_set(None, a).is_confirmed_by(&slots));
        assert!(Command::position_slave_set(None, b).is_confirmed_by(&slots));
        let single = Report::position_slave_set(SlaveAddresses::Single(a));
        assert!(Command::position_slave_set(None, a).is_confirmed_by(&single));
        assert!(Command::position_slave_set(Some(Slot::default()), a).is_confirmed_by(&single));
        // A spec-form report says nothing of slot 2.
        assert!(!Command::position_slave_set(Some(slot2), a).is_confirmed_by(&single));
        assert_eq!(
            Command::position_slave_set(Some(slot2), a).confirmation(&single),
            Confirmation::Unknown
        );
        assert_eq!(
            Command::position_slave_set(None, b).confirmation(&single),
            Confirmation::NotTaken
        );
    }

    #[test]
    fn a_time_is_confirmed_from_itself_to_the_window_past_it() {
        let set = Command::time(1_000);
        for (reported, confirmed) in [
            (999, false),
            (1_000, true),
            (1_000 + TIME_CONFIRM_WINDOW, true),
            (1_001 + TIME_CONFIRM_WINDOW, false),
            (0, false),
            (u32::MAX, false),
        ] {
            assert_eq!(
                set.is_confirmed_by(&Report::time(reported)),
                confirmed,
                "{reported}"
            );
        }
        assert!(Command::time(u32::MAX).is_confirmed_by(&Report::time(u32::MAX)));
    }

    #[test]
    fn a_trajectory_is_confirmed_by_the_same_waypoints_alone() {
        let w = |time| Waypoint {
            time,
            elevator: 0.5,
            aileron: -0.25,
            altitude: 2.0,
        };
        fn build<'a>(buf: &'a mut [u8; 64], is_command: bool, waypoints: &[Waypoint]) -> &'a [u8] {
            let mut builder = match is_command {
                true => TrajectoryBuilder::command(buf).unwrap(),
                false => TrajectoryBuilder::report(buf).unwrap(),
            };
            for waypoint in waypoints {
                builder.push(*waypoint).unwrap();
            }
            let len = builder.finish();
            &buf[..len]
        }
        let mut bufs = [[0u8; 64]; 4];
        let [command, report, fewer, other] = &mut bufs;
        let Ok(crate::Packet::Command(command)) = crate::parse(build(command, true, &[w(1), w(2)]))
        else {
            panic!("a trajectory set command");
        };
        for (report, confirmed) in [
            (build(report, false, &[w(1), w(2)]), true),
            (build(fewer, false, &[w(1)]), false),
            (build(other, false, &[w(1), w(3)]), false),
        ] {
            let Ok(crate::Packet::Report(report)) = crate::parse(report) else {
                panic!("a trajectory report");
            };
            assert_eq!(command.is_confirmed_by(&report), confirmed, "{report:?}");
        }
    }
}
