//! A set command and the MAV's word that it took it: [`CommandSender::send_confirmed`].

use std::time::Duration;

use bytes::Bytes;
use mcp_core::{Command, CommandType, Confirmation, Report, StatusRequest, Waypoint, Waypoints};
use tokio::time::Instant;
use xbee_api::Address64;

use crate::{CommandSender, DeliveryReport, RequestError, SendError, SendOptions};

/// How many times [`CommandSender::confirm`] asks for the report at most: again while
/// a report does not confirm the command, in case it was one the MAV sent before it
/// took the command (a landing's state changes, reported as they come).
const ASKS: usize = 3;

/// A command delivered, and the MAV's report that says it took it.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Confirmed {
    /// The radio's delivery status of the command.
    pub delivery: DeliveryReport,
    /// The MAV's report, which confirms the command
    /// ([`Command::is_confirmed_by`]).
    pub report: Report<Bytes>,
}

/// The delivery, then the report: `delivered (16-bit address 7d84, frame id 1, retries
/// 0, discovery no_discovery_overhead); report: landing landing`.
impl std::fmt::Display for Confirmed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}; report: {}", self.delivery, self.report)
    }
}

/// Why [`CommandSender::send_confirmed`] could not confirm a command.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConfirmError {
    /// The command has no status request to confirm it (position set), or is one.
    /// Nothing was sent.
    #[error(
        "{} cannot be confirmed: {}",
        match status_request {
            true => "a status request",
            false => "a position_set command",
        },
        match status_request {
            true => "send it with `request`, which waits for its report",
            false => "it has no status request, and no report says whether a MAV took it",
        }
    )]
    Unconfirmable {
        /// The command's type.
        command_type: CommandType,
        /// Whether the command is a status request.
        status_request: bool,
    },
    /// The command was to broadcast: one report could not speak for every MAV.
    /// Nothing was sent.
    #[error(
        "a broadcast command cannot be confirmed (one MAV's report does not speak for the \
         others): send it to each MAV"
    )]
    Broadcast,
    /// The command was not delivered (or its delivery not known): the radio's
    /// refusal, no status in time, the link down.
    #[error("{0}")]
    Send(SendError),
    /// No report came to say what the MAV did (the status request failed, or went
    /// unanswered).
    #[error("no report to confirm the command: {0}")]
    Request(RequestError),
    /// The MAV reported another state than the command sets, each time it was asked:
    /// it did not take the command (an unknown controller, fewer waypoints than sent),
    /// or something changed it back meanwhile (another ground station, the MAV
    /// itself).
    #[error("the MAV did not take the command: it reports {report}")]
    #[non_exhaustive]
    NotTaken {
        /// The last report, which does not confirm the command.
        report: Report<Bytes>,
    },
    /// The MAV's report cannot say whether it took the command
    /// ([`Confirmation::Unknown`]): a MAV that reports its slave addresses in the
    /// spec's form (slot 0's alone) asked of another slot, or a landing state outside
    /// the protocol's table.
    #[error("the MAV's report cannot say whether it took the command: it reports {report}")]
    #[non_exhaustive]
    Unverifiable {
        /// The report.
        report: Report<Bytes>,
    },
}

impl ConfirmError {
    /// Whether the command or the report ran out of time: the MAV may have taken the
    /// command, and asking again ([`CommandSender::confirm`]) may tell.
    pub fn is_timeout(&self) -> bool {
        match self {
            ConfirmError::Send(e) => e.is_timeout(),
            ConfirmError::Request(e) => e.is_timeout(),
            _ => false,
        }
    }

    /// Whether the command or the report failed because the link is down or ended, as
    /// [`SendError::is_link_down`] says: the MAV may have taken the command if it went
    /// out before, and asking again ([`CommandSender::confirm`]) once the link is back
    /// may tell.
    ///
    /// ```
    /// use mcp_host::{ConfirmError, SendError};
    /// assert!(ConfirmError::Send(SendError::Closed).is_link_down());
    /// assert!(!ConfirmError::Broadcast.is_link_down());
    /// ```
    pub fn is_link_down(&self) -> bool {
        match self {
            ConfirmError::Send(e) => e.is_link_down(),
            ConfirmError::Request(e) => e.is_link_down(),
            _ => false,
        }
    }
}

impl CommandSender {
    /// Sends a set command to the MAV at `to`, waits for the radio's delivery status,
    /// then asks the MAV whether it took it ([`confirm`](Self::confirm)): the matching
    /// status request, whose report must show the command taken. MCP set commands get
    /// no reply of their own: this is how a ground station knows a MAV landed,
    /// switched controller or took a trajectory.
    ///
    /// Each wait (the delivery status, then each report asked for, three at most) takes
    /// the link's [`send_timeout`](crate::LinkOptions::send_timeout); see
    /// [`send_confirmed_with`](Self::send_confirmed_with). A time command is confirmed
    /// by a time report no further past the time set than the seconds since the command
    /// went (and one more).
    ///
    /// Fails with [`ConfirmError::Unconfirmable`] for a position set or a status
    /// request and [`ConfirmError::Broadcast`] to [`Address64::BROADCAST`] (nothing is
    /// sent), [`ConfirmError::Send`] when the command was not delivered,
    /// [`ConfirmError::Request`] when no report came, [`ConfirmError::NotTaken`] when
    /// the MAV reports another state, and [`ConfirmError::Unverifiable`] when its
    /// report cannot say.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::mcp_core::{Command, Controller};
    /// use mcp_host::ConfirmError;
    ///
    /// let mav = "0013A20040B599B9".parse()?;
    /// match sender.send_confirmed(mav, &Command::controllers(Controller::Mpc)).await {
    ///     Ok(confirmed) => println!("the MAV reports {}", confirmed.report),
    ///     Err(ConfirmError::NotTaken { report, .. }) => println!("not taken: {report}"),
    ///     Err(e) if e.is_timeout() => println!("no word from the MAV: {e}"),
    ///     Err(e) => return Err(e.into()),
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub async fn send_confirmed<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &Command<B>,
    ) -> Result<Confirmed, ConfirmError> {
        self.send_confirmed_with(to, command, None).await
    }

    /// [`CommandSender::send_confirmed`] with a timeout for each wait (`None`: the
    /// link's default).
    pub async fn send_confirmed_with<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &Command<B>,
        timeout: Option<Duration>,
    ) -> Result<Confirmed, ConfirmError> {
        let request = confirming_request(to, command)?;
        let options = SendOptions {
            timeout,
            ..SendOptions::default()
        };
        let sent = Instant::now();
        let delivery = self
            .send_with(to, command, options)
            .await
            .map_err(ConfirmError::Send)?;
        let report = self
            .ask_until_confirmed(to, command, request, timeout, Some(sent))
            .await?;
        Ok(Confirmed { delivery, report })
    }

    /// [`send_confirmed`](Self::send_confirmed) of a trajectory set command of
    /// `waypoints`, as [`send_trajectory`](Self::send_trajectory) sends: confirmed by
    /// the MAV's trajectory report listing the same waypoints. More than 15 do not fit
    /// a payload: [`ConfirmError::Send`] with [`SendError::TooLarge`], nothing sent.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::mcp_core::Waypoint;
    ///
    /// let mav = "0013A20040B599B9".parse()?;
    /// let waypoint = Waypoint { time: 1_700_000_000, elevator: 0.5, aileron: 0.0, altitude: 1.2 };
    /// let confirmed = sender.send_trajectory_confirmed(mav, &[waypoint]).await?;
    /// println!("the MAV reports {}", confirmed.report);
    /// # Ok(())
    /// # }
    /// ```
    pub async fn send_trajectory_confirmed(
        &self,
        to: Address64,
        waypoints: &[Waypoint],
    ) -> Result<Confirmed, ConfirmError> {
        let bytes: Vec<u8> = waypoints.iter().flat_map(Waypoint::to_bytes).collect();
        let command = Command::TrajectorySet(Waypoints::new_unchecked(bytes));
        self.send_confirmed(to, &command).await
    }

    /// Asks the MAV at `to` whether it took `command`, sent before (by
    /// [`send`](Self::send), fire and forget, or by another program): the matching
    /// status request ([`Command::confirming_request`]), and its report if it shows the
    /// command taken ([`Command::confirmation`]). While a report does not, it is asked
    /// for again (it may have been sent before the MAV took the command), three times
    /// in all, before the command is said [`NotTaken`](ConfirmError::NotTaken); a
    /// report that came is not lost to a later request that fails. Each report is
    /// waited for the link's [`send_timeout`](crate::LinkOptions::send_timeout). A time
    /// command is confirmed by a time report up to
    /// [`TIME_CONFIRM_WINDOW`](mcp_core::TIME_CONFIRM_WINDOW) seconds past the time set:
    /// this call does not know when the command went.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::mcp_core::Command;
    /// use mcp_host::{FrameId, SendOptions};
    ///
    /// let mav = "0013A20040B599B9".parse()?;
    /// let land = Command::landing(true);
    /// let forget = SendOptions { frame_id: FrameId::None, ..SendOptions::default() };
    /// sender.send_with(mav, &land, forget).await?;
    /// let report = sender.confirm(mav, &land).await?;
    /// println!("the MAV reports {report}");
    /// # Ok(())
    /// # }
    /// ```
    pub async fn confirm<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &Command<B>,
    ) -> Result<Report<Bytes>, ConfirmError> {
        self.confirm_with(to, command, None).await
    }

    /// [`CommandSender::confirm`] with a timeout for each report (`None`: the link's
    /// default).
    pub async fn confirm_with<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &Command<B>,
        timeout: Option<Duration>,
    ) -> Result<Report<Bytes>, ConfirmError> {
        let request = confirming_request(to, command)?;
        self.ask_until_confirmed(to, command, request, timeout, None)
            .await
    }

    /// Asks `request` of `to` until a report confirms `command`, [`ASKS`] times at
    /// most; a time report no further past the time set than the seconds since `sent`.
    async fn ask_until_confirmed<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &Command<B>,
        request: StatusRequest,
        timeout: Option<Duration>,
        sent: Option<Instant>,
    ) -> Result<Report<Bytes>, ConfirmError> {
        let mut not_taken = None;
        let mut asked = 0;
        loop {
            let report = match self.request_with(to, request, timeout).await {
                Ok(report) => report,
                // A report that came says more than a request that failed after it.
                Err(error) => {
                    return Err(match not_taken {
                        Some(report) => ConfirmError::NotTaken { report },
                        None => ConfirmError::Request(error),
                    });
                }
            };
            asked += 1;
            match judge(command, &report, sent) {
                Confirmation::Taken => return Ok(report),
                Confirmation::Unknown => return Err(ConfirmError::Unverifiable { report }),
                Confirmation::NotTaken if asked >= ASKS => {
                    return Err(ConfirmError::NotTaken { report });
                }
                Confirmation::NotTaken => not_taken = Some(report),
            }
        }
    }
}

/// What `report` says of `command` ([`Command::confirmation`]), a time report held to
/// the seconds since `sent` (rounded up, and one more for the MAV's clock ticking over
/// meanwhile): a MAV whose clock was already a little ahead did not take it.
fn judge<B: AsRef<[u8]>>(
    command: &Command<B>,
    report: &Report<Bytes>,
    sent: Option<Instant>,
) -> Confirmation {
    let confirmation = command.confirmation(report);
    if let (Command::Time(set), Report::Time(time), Some(sent), Confirmation::Taken) =
        (command, report, sent, confirmation)
    {
        let since = sent.elapsed().as_secs().saturating_add(2);
        if u64::from(time.saturating_sub(*set)) > since {
            return Confirmation::NotTaken;
        }
    }
    confirmation
}

/// The status request that confirms `command` to `to`, or why there is none.
fn confirming_request<B: AsRef<[u8]>>(
    to: Address64,
    command: &Command<B>,
) -> Result<StatusRequest, ConfirmError> {
    let Some(request) = command.confirming_request() else {
        return Err(ConfirmError::Unconfirmable {
            command_type: command.command_type(),
            status_request: command.is_status_request(),
        });
    };
    match to {
        Address64::BROADCAST => Err(ConfirmError::Broadcast),
        _ => Ok(request),
    }
}
