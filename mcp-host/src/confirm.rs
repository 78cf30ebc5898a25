//! A set command and the MAV's word that it took it: [`CommandSender::send_confirmed`].

use std::time::Duration;

use bytes::Bytes;
use mcp_core::{Command, CommandType, Report, StatusRequest};
use xbee_api::Address64;

use crate::{CommandSender, DeliveryReport, RequestError, SendError, SendOptions};

/// How many times [`CommandSender::send_confirmed`] asks for the report: a second time
/// if the first report does not confirm the command, in case it was one the MAV sent
/// before it took the command.
const ASKS: usize = 2;

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
    /// The command was delivered, but no report came back to say what the MAV did.
    #[error("the command was delivered, but {0}")]
    Request(RequestError),
    /// The MAV reported another state than the command sets: it did not take the
    /// command (an unknown controller, fewer waypoints than sent), or something
    /// changed it back meanwhile (another ground station, the MAV itself).
    #[error("the MAV did not take the command: it reports {report}")]
    #[non_exhaustive]
    NotTaken {
        /// The last report, which does not confirm the command.
        report: Report<Bytes>,
    },
}

impl ConfirmError {
    /// Whether the command or the report ran out of time: the MAV may have taken the
    /// command, and asking again ([`CommandSender::request`]) may tell.
    pub fn is_timeout(&self) -> bool {
        match self {
            ConfirmError::Send(e) => e.is_timeout(),
            ConfirmError::Request(e) => e.is_timeout(),
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
    /// Each of the two waits (the delivery status, each report) takes the link's
    /// [`send_timeout`](crate::LinkOptions::send_timeout); see
    /// [`send_confirmed_with`](Self::send_confirmed_with).
    ///
    /// Fails with [`ConfirmError::Unconfirmable`] for a position set or a status
    /// request and [`ConfirmError::Broadcast`] to [`Address64::BROADCAST`] (nothing is
    /// sent), [`ConfirmError::Send`] when the command was not delivered,
    /// [`ConfirmError::Request`] when no report came, and
    /// [`ConfirmError::NotTaken`] when the MAV reports another state.
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
        confirming_request(to, command)?;
        let options = SendOptions {
            timeout,
            ..SendOptions::default()
        };
        let delivery = self
            .send_with(to, command, options)
            .await
            .map_err(ConfirmError::Send)?;
        let report = self.confirm_with(to, command, timeout).await?;
        Ok(Confirmed { delivery, report })
    }

    /// Asks the MAV at `to` whether it took `command`, sent before (by
    /// [`send`](Self::send), fire and forget, or by another program): the matching
    /// status request ([`Command::confirming_request`]), and its report if it shows the
    /// command taken ([`Command::is_confirmed_by`]). A report that does not is asked
    /// for once more (it may have been sent before the MAV took the command) before the
    /// command is said [`NotTaken`](ConfirmError::NotTaken). Each report is waited for
    /// the link's [`send_timeout`](crate::LinkOptions::send_timeout).
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
        let mut asked = 0;
        loop {
            let report = self
                .request_with(to, request, timeout)
                .await
                .map_err(ConfirmError::Request)?;
            asked += 1;
            if command.is_confirmed_by(&report) {
                return Ok(report);
            }
            if asked == ASKS {
                return Err(ConfirmError::NotTaken { report });
            }
        }
    }
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
