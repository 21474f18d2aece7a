//! What a procedure changes on the device for its own purpose, kept and put
//! back on every way out: the accepted drive, the drive mode, the
//! displacement options and whether the drive runs. `identify` drives each
//! transducer alone in voltage mode, a sweep steps the drive; whether they
//! end, fail, are refused by the device or are interrupted (SIGINT,
//! SIGTERM), the device is left as it was found ([`restoring`]).

use board::device::{DisplacementOptions, DriveMode, DriveSetting};
use board::protocol::{Request, Response};

use crate::answers::{expect, unexpected};
use crate::client::Client;
use crate::{Error, Result};

/// The device's state a procedure may change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceState {
    /// The accepted drive.
    pub drive: DriveSetting,
    /// Voltage or displacement mode.
    pub mode: DriveMode,
    /// The displacement mode's tracking and headroom.
    pub options: DisplacementOptions,
    /// The drive runs (started, not stopped).
    pub running: bool,
}

impl DeviceState {
    /// Reads it (`GetDrive`, `GetStatus`).
    ///
    /// # Errors
    /// A lost link or an unexpected answer.
    pub fn read(c: &mut Client) -> Result<DeviceState> {
        let drive = match expect(c.call(Request::GetDrive)?)? {
            Response::Drive { setting, .. } => setting,
            other => return Err(unexpected(other)),
        };
        match expect(c.call(Request::GetStatus)?)? {
            Response::Status(s) => Ok(DeviceState {
                drive,
                mode: s.mode,
                options: s.options,
                running: s.running,
            }),
            other => Err(unexpected(other)),
        }
    }

    /// Puts it back: the mode, the drive, the options, then start or stop —
    /// only what differs from the device's state now. The mode goes first
    /// (the drive is then accepted as it was, in its own mode); should the
    /// device refuse to re-plan the drive now in force in that mode, the
    /// drive goes first, in voltage mode.
    ///
    /// # Errors
    /// A request the device refuses (e.g. the displacement mode after its
    /// transducers were forgotten) or a lost link; the message says what is
    /// in force then.
    pub fn restore(&self, c: &mut Client) -> Result<()> {
        let now = DeviceState::read(c)?;
        if now == *self {
            return Ok(());
        }
        if now.mode != self.mode && expect(c.call(Request::SetDriveMode(self.mode))?).is_err() {
            expect(c.call(Request::SetDriveMode(DriveMode::OpenLoop))?)?;
            expect(c.call(Request::SetDrive(self.drive))?)?;
            expect(c.call(Request::SetDriveMode(self.mode))?)?;
        }
        if DeviceState::read(c)?.drive != self.drive {
            expect(c.call(Request::SetDrive(self.drive))?)?;
        }
        if now.options != self.options {
            expect(c.call(Request::SetDisplacementOptions(self.options))?)?;
        }
        match (now.running, self.running) {
            (false, true) => {
                expect(c.call(Request::Start)?)?;
            }
            (true, false) => {
                expect(c.call(Request::Stop)?)?;
            }
            _ => {}
        }
        Ok(())
    }
}

/// Runs `body` and puts the device back as it was before, whatever the way
/// out: its result, an error, the device's refusal or an interruption (the
/// restoring requests ignore the interrupt flag). A failure to restore is
/// said in the error.
///
/// # Errors
/// `body`'s error (with the restoring's failure appended, if any), or the
/// restoring's failure after a `body` that succeeded.
pub fn restoring<T>(c: &mut Client, body: impl FnOnce(&mut Client) -> Result<T>) -> Result<T> {
    let before = DeviceState::read(c)?;
    let r = body(c);
    let back = c.uninterrupted(|c| before.restore(c));
    match (r, back) {
        (r, Ok(())) => r,
        (Ok(_), Err(b)) => Err(Error::failure(format!(
            "the device could not be put back as it was ({}); `fricctl device drive get` and `status` show it",
            b.msg
        ))),
        (Err(e), Err(b)) => Err(Error {
            code: e.code,
            msg: format!(
                "{}; and the device could not be put back as it was ({})",
                e.msg, b.msg
            ),
        }),
    }
}

/// Runs `body`, which changes the device in several requests (e.g. the
/// mode, the options, then the drive), all or nothing: when it fails —
/// the device refuses a later request, the link fails, an interruption —
/// the device is put back as it was before; when it succeeds its changes
/// stay. A failure to restore is said in the error.
///
/// # Errors
/// `body`'s error (with the restoring's failure appended, if any).
pub fn all_or_nothing<T>(c: &mut Client, body: impl FnOnce(&mut Client) -> Result<T>) -> Result<T> {
    let before = DeviceState::read(c)?;
    let e = match body(c) {
        Ok(t) => return Ok(t),
        Err(e) => e,
    };
    match c.uninterrupted(|c| before.restore(c)) {
        Ok(()) => Err(e),
        Err(b) => Err(Error {
            code: e.code,
            msg: format!(
                "{}; and the device could not be put back as it was ({})",
                e.msg, b.msg
            ),
        }),
    }
}
