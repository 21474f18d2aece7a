"""fricctl: dual-mode (normal + tangential) ultrasonic friction control.

The exact steady-state solver of the Popov & Li single-spring model (and its
lift-off and curved-profile extensions) from Python. Every number comes from
the same Rust library as the command-line tool ``fricctl``; every keyword is
one of its flags with underscores (``--phi-deg`` is ``phi_deg``); every
refusal names the keyword first, then gives the CLI's one-line message
(``phi_deg: --phi-deg: must be of magnitude ≤ 1e100 (got inf)``), raised as
``ValueError`` (bad input), ``TypeError`` (a value of the wrong type: a
string, None or a list for a number, a float for a count), ``OverflowError``
(a count beyond its type, ``steps_per_period: must be ≤ 4294967295 (got
…)``, or an int beyond a float's range, ``mu0: an int of 401 digits is
beyond the range of a float``) or :class:`SolverError` (a computation that
failed).

Units: SI (m, N/m, Hz, m/s), or the paper's dimensionless groups (eqs.
25/26: ``duz_rel``, ``dux_rel``, ``ratio``), with which μ0 = kz = kx = uz0 =
ω = 1 and velocities are in units of ωW0 = ω μ0 kz uz0 / kx.
"""

from os import PathLike
from typing import Any, Dict, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
Method = Literal["auto", "exact", "fixed", "approx"]
Errors = Literal["raise", "nan"]

class SolverError(RuntimeError):
    """A solver could not produce a result within its bound (the CLI's exit
    status 1): the drive is ill-conditioned in f64, a fixed-step run did not
    reach a steady state, or no method meets the tolerance asked."""

class Record:
    """A result whose fields are plain attributes, named and in the order of
    the CLI's ``--json`` keys (same quantities, same units)."""

    def __getattr__(self, name: str) -> Any: ...
    def to_dict(self) -> Dict[str, Any]:
        """The fields as a dict, in order."""

class Scene:
    """A contact, its drive and its profile, checked as the CLI checks its
    scene flags. Immutable: one Scene may be used from many threads.

    Give either the physical quantities (SI units) or the dimensionless
    groups.

    Args:
        mu0: local coefficient of friction μ0 (> 0).
        kz: normal contact stiffness k_z, N/m (for a curved profile E*).
        kx: tangential contact stiffness k_x, N/m (for a curved profile G*).
        uz0: mean indentation u_z0, m.
        duz: normal oscillation amplitude Δu_z, m (≥ uz0: lift-off once per
            period, eq. L4).
        dux: tangential oscillation amplitude Δu_x, m.
        freq: drive frequency f, Hz (or ``omega``, rad/s).
        omega: drive angular frequency ω, rad/s.
        phi_deg: phase φ of the tangential oscillation, degrees (default 0;
            or ``phi_rad``).
        phi_rad: phase φ, radians.
        duz_rel: dimensionless Δu_z/u_z0 (eq. 25).
        dux_rel: dimensionless k_xΔu_x/(μ0 k_z u_z0) (eq. 25).
        ratio: dimensionless k_xΔu_x/(μ0 k_z Δu_z) (eq. 26, instead of dux_rel).
        profile: "flat" (default, the paper's punch), "sphere", "cone" or
            "power" (method of dimensionality reduction).
        exponent: n of the power profile f = c·rⁿ (n > 0).
        scene: a TOML scene file (keys as the keywords); keywords override it.
        liftoff: admit Δu_z ≥ u_z0 (default True); False refuses it as the
            permanent-contact commands do.

    Raises:
        ValueError: a parameter out of its domain, named by its keyword and
            then the CLI's text (``mu0: --mu0: must be > 0 (got -1)``).
        TypeError: a value that is not a number (``argument 'mu0': must be
            real number, not str``).
    """

    def __init__(
        self,
        *,
        mu0: Optional[float] = None,
        kz: Optional[float] = None,
        kx: Optional[float] = None,
        uz0: Optional[float] = None,
        duz: Optional[float] = None,
        dux: Optional[float] = None,
        freq: Optional[float] = None,
        omega: Optional[float] = None,
        phi_deg: Optional[float] = None,
        phi_rad: Optional[float] = None,
        duz_rel: Optional[float] = None,
        dux_rel: Optional[float] = None,
        ratio: Optional[float] = None,
        profile: Optional[Literal["flat", "sphere", "cone", "power"]] = None,
        exponent: Optional[float] = None,
        scene: Optional[Union[str, PathLike[str]]] = None,
        liftoff: bool = True,
    ) -> None: ...
    @overload
    def mu(
        self,
        v0: float,
        method: Method = "auto",
        tol: Optional[float] = None,
        steps_per_period: Optional[int] = None,
        return_bound: Literal[False] = False,
        errors: Errors = "raise",
    ) -> float: ...
    @overload
    def mu(
        self,
        v0: float,
        method: Method = "auto",
        tol: Optional[float] = None,
        steps_per_period: Optional[int] = None,
        *,
        return_bound: Literal[True],
        errors: Errors = "raise",
    ) -> Tuple[float, float]: ...
    @overload
    def mu(
        self,
        v0: ArrayLike,
        method: Method = "auto",
        tol: Optional[float] = None,
        steps_per_period: Optional[int] = None,
        return_bound: bool = False,
        errors: Errors = "raise",
    ) -> Any: ...
    def mu(
        self,
        v0: Any,
        method: Method = "auto",
        tol: Optional[float] = None,
        steps_per_period: Optional[int] = None,
        return_bound: bool = False,
        errors: Errors = "raise",
    ) -> Any:
        """The steady-state coefficient of friction μ = ⟨F_x⟩/⟨F_z⟩ at sliding
        velocity ``v0`` (m/s; units of ωW0 for a dimensionless scene).

        ``v0`` a number (Python or numpy, not a bool) gives a float; any
        array-like of integers or floats gives an ndarray of the same shape
        (a 0-d array a 0-d array), computed in parallel without the GIL and
        written straight into the result: the peak memory grows by the
        result's size (and a float64 copy of an input that is not one), 78 MB
        for 10⁷ velocities (python/README.md). ``|μ| ≤ μ0``; μ = ±μ0 beyond
        the critical velocities (eq. 8).

        Args:
            method: "auto" (the cheapest method whose guaranteed bound is
                within ``tol``: ±μ0 beyond v_c, eq. 21/24, the exact solver),
                "exact" (the event-driven steady-state solver), "fixed" (the
                paper's fixed-step scheme, §3), "approx" (eq. 21 or eq. 24).
            tol: the error bound asked of "auto", in units of μ0.
            steps_per_period: steps of "fixed" (default 10000): an int in
                [1, 2³² − 1].
            return_bound: also return the guaranteed error bound of each μ
                (units of μ): a pair (μ, bound).
            errors: "raise" (default) raises on the first failure; "nan"
                returns NaN there with a RuntimeWarning (solver failures, and
                v0 NaN or ±inf).

        At v0 = 0 μ is two-sided (any value in [μ(0⁻), μ(0⁺)] holds the body):
        NaN with a RuntimeWarning pointing to :meth:`mu_limits` (with lift-off
        μ(0) is unique and returned).

        Raises:
            ValueError: a bad argument, its keyword then the CLI's text
                (``v0: --v0: must be of magnitude ≤ 1e100 (got inf)``); for an
                array the first bad element's index (C order) is appended,
                ``(at v0[3])``.
            TypeError: ``v0`` not numbers (None, a string — numpy would read
                "0.01" —, a bool, a complex number, an array of strings or
                objects): ``v0: expected a number or an array of numbers,
                got str``; a ``steps_per_period`` that is not an int.
            OverflowError: ``steps_per_period`` beyond 2³² − 1, named.
            SolverError: a solver failure, or a ``tol`` no method meets.
        """
    def critical_velocity(self) -> Tuple[float, float]:
        """(forward, backward) critical velocities v_c, v_c' in m/s (eq. 8;
        the contact window's, eq. L5, with lift-off): beyond them the contact
        slides through the whole period and μ = ±μ0."""
    def mu_limits(self) -> Tuple[float, float]:
        """(μ(0⁻), μ(0⁺)): the limits of μ as v0 → 0 from below and above
        (the static analysis; equal with lift-off)."""
    def static_interval(self) -> Optional[Tuple[float, float]]:
        """The exact static interval of the equilibrium displacement u_x0
        (lo, hi) in m (``fricctl static``'s interval_lo_m, interval_hi_m);
        None when it is empty or the contact lifts off. Flat punch only
        (ValueError for a curved profile, whose static interval is the held
        force μ/μ0 in [μ(0⁻), μ(0⁺)]: ``mu_limits``)."""
    def regime(self, v0: float) -> Literal["rest", "stick_slip", "sliding"]:
        """The contact's state at sliding velocity v0: "rest" (v0 = 0),
        "stick_slip" (|v0| below the critical velocity of its direction) or
        "sliding" (|μ| = μ0)."""
    def classify(self) -> Record:
        """The scene's regime as ``fricctl classify``: ``regime``
        (active_control, dynamic_ratchet, actuator), mu_0plus_over_mu0,
        mu_0minus_over_mu0, vc_forward, vc_backward (m/s), asymmetry
        (max|μ(v)+μ(−v)|/μ0)."""
    @property
    def lifts_off(self) -> bool:
        """Whether Δu_z ≥ u_z0 (the contact lifts off once per period)."""
    @property
    def dimensionless(self) -> bool:
        """Whether the scene was given by its dimensionless groups."""
    @property
    def profile(self) -> str:
        """flat, sphere, cone or power."""
    @property
    def mu0(self) -> float:
        """μ0."""
    @property
    def w0(self) -> float:
        """W0 = μ0 k_z u_z0/k_x, m: the unit of the tangential amplitude (eq. 25)."""
    @property
    def velocity_scale(self) -> float:
        """ωW0, m/s: the unit of dimensionless velocities."""

def tune(
    scene: Scene,
    *,
    adjust: Literal["duz", "dux", "phase"],
    target_mu_rel: Optional[float] = None,
    target_mu: Optional[float] = None,
    maximize: Optional[Literal["asymmetry", "stall-force"]] = None,
    v0: Optional[float] = None,
    v_rel: Optional[float] = None,
    max_duz: Optional[float] = None,
    max_dux: Optional[float] = None,
    liftoff_margin: float = 0.05,
) -> Record:
    """Inverse design (``fricctl tune``): the Δu_z, Δu_x (m) or φ (deg) that
    attains a target μ at sliding velocity ``v0`` (m/s), or ``v_rel`` times the
    scene's critical velocity v_c as given (forward for v_rel > 0, backward
    for v_rel < 0) (``target_mu_rel`` = μ/μ0
    in (−1, 1), or ``target_mu``), or that maximises the ratchet asymmetry or
    the forward stall force, with every drive keeping Δu_z ≤
    (1 − liftoff_margin)·u_z0. Permanent-contact scenes; a scene with a
    curved profile (sphere, cone, power) is searched on its MDR quadrature
    (``method`` = ``"mdr"``, the keys ``profile`` and ``exponent`` name it).

    The result's fields are ``fricctl tune --json``'s keys (duz, dux, phi_deg,
    mu, residual_over_mu0, error_bound_over_mu0, solutions, …). A residual
    beyond the solver's bound gives a RuntimeWarning (the CLI's exit 1).
    """

def fit(
    data: Union[str, PathLike[str], Mapping[str, ArrayLike], Any],
    params: Optional[Union[str, Sequence[str]]] = None,
) -> Record:
    """Identification (``fricctl fit``): μ0 and k_x/k_z fitted to a measured
    sweep by weighted least squares with the exact solver, with 95 %
    intervals (Student t).

    Args:
        data: a sweep file (``fricctl device sweep --csv``), or its columns as
            a dict of arrays or a pandas DataFrame: freq_hz (Hz), amp_z,
            amp_x, offset_z (m), phi_deg (°), v0 (m/s), model_mu0, model_kz,
            model_kx (the device model's contact), measured_mu; optional
            std_error (0 = unknown: unweighted), valid (rows with 0 are
            skipped), value (the swept value, for the residuals).
        params: "mu0,kx_over_kz" (default), or a list of those names.

    The result's fields are ``fricctl fit --json``'s keys (mu0,
    mu0_ci95_low, mu0_ci95_high, kx_over_kz, …, chi2, dof, chi2_p_value,
    doubtful), plus the arrays residual_value, residual_mu,
    residual_std_error. With standard errors, a χ² whose p-value
    ``chi2_p_value`` is below 1e-6 (the model does not describe the data
    within their errors; docs/guide/fit.md) makes the fit doubtful: the
    verdict is ``doubtful`` and a RuntimeWarning (the CLI's exit 1).

    Raises:
        TypeError: ``data`` neither a path nor a mapping of columns
            (``data: expected a sweep file path, a dict of arrays or a
            pandas DataFrame, got NoneType``), a column that is not numbers,
            ``params`` not text.
        ValueError: a bad row or parameter, by keyword then the CLI's text
            (``data: --data: line 4: v0 must be of magnitude ≤ 1e100 (got
            1e300)``).
    """

def load_line(scene: Scene) -> Record:
    """The contact as an actuator (``fricctl load-line``): stall forces (N),
    no-load velocities (m/s), the operating points of maximum power and of
    maximum efficiency, for any contact (flat, lift-off, curved). Fields:
    ``fricctl load-line --json``'s keys."""

def motion(
    scene: Scene,
    *,
    mass: float,
    force_amp_rel: float,
    force_omega: float,
    force_offset_rel: float = 0.0,
    spring: float = 0.0,
    duration: Optional[float] = None,
    method: Literal["auto", "homogenised", "resolved"] = "auto",
    tol: float = 1e-3,
) -> Record:
    """A body of mass M (kg) on the vibrated contact under the slow force
    F(t) = μ0·F̄z·(f0 + f·sin Ωt) (``fricctl motion``): the drift, its error
    estimate, the stick fraction, and the trajectory of the last ≤ 50 load
    periods as arrays t (s), x (m), v (m/s), force (N), stuck (bool).

    Fields: ``fricctl motion --json``'s keys, plus those arrays and
    ``doubtful`` (the CLI's exit-1 message, or None; it is also issued as a
    RuntimeWarning).
    """

class DeviceError(RuntimeError):
    """A device operation failed (the base of DeviceRefused, DeviceFault and
    LinkError; the CLI's exit status 1)."""

class DeviceRefused(DeviceError):
    """The device refused a request. ``kind`` ('OutOfRange', 'LiftOffRefused',
    'NotIdentified', 'NotRunning', 'Busy', 'BadScene', 'OutOfReach', …);
    for a range refusal ``param`` (the wire name, e.g. 'Freq') and ``min``,
    ``max`` in the parameter's SI unit, else None. The message names the
    keyword, then the CLI's text (``freq: --freq: refused by the device:
    allowed range [1000, 100000]``)."""

    kind: str
    param: Optional[str]
    min: Optional[float]
    max: Optional[float]

class DeviceFault(DeviceError):
    """The device latched a fault (the message names its bits)."""

class LinkError(DeviceError):
    """The link failed: no answer, a closed connection, a port or address
    that cannot be opened, a closed Device."""

SweepParam = Literal["phase_deg", "amp_z", "amp_x", "offset_z", "freq"]

class Device:
    """A board, the QEMU firmware or the virtual device, driven through the
    same library as ``fricctl device …``: the same requests and procedures,
    each answer a :class:`Record` with the CLI's ``--json`` keys
    (docs/device-json.md). Device I/O runs with the GIL released. A
    KeyboardInterrupt ends a call at its next request; ``identify`` and
    ``sweep`` put back what they changed (drive, mode, options, running)
    before it is raised. Use it as a context manager (``with ... as dev``).

    Counts (``periods``, ``points``, ``count``, ``seed``, ``timeout_ms``, …)
    are ints: a negative one is a ValueError, one beyond its type an
    OverflowError, a float or a bool a TypeError, each naming the keyword
    (``periods: must be ≤ 4294967295 (got …)``)."""

    @staticmethod
    def virtual(
        *,
        plant: Optional[Mapping[str, Union[float, bool]]] = None,
        v0: float = 0.004,
        noise: float = 1.0,
        offset: float = 0.0,
        seed: int = 0,
    ) -> "Device":
        """The in-process virtual device (``fricctl device --sim`` without a
        state file): the board's logic on the simulated plant, its device
        time as fast as the host computes. ``plant`` takes the
        ``sim-device`` plant flags without ``--plant-`` and with ``_``:
        ``mu0``, ``kz`` (N/m), ``kx`` (N/m), ``lag_periods``, ``mu0_drift``
        (1/s), ``ideal_transducers``, ``resonance_z``/``_x`` (Hz),
        ``q_z``/``_x``, ``gain_z``/``_x`` (m/V), ``resonance_drift_z``/``_x``
        (Hz/s), ``thermal_shift`` (Hz/µm²), ``crosstalk``, ``load_q``,
        ``v0_profile`` (a CSV path, rows ``t_s,v0_m_s``). ``v0``
        is the stage velocity (m/s), ``noise`` and ``offset`` the ADC's
        (counts), ``seed`` the noise record (0: the default)."""
    @staticmethod
    def open(
        port: Optional[str] = None,
        *,
        tcp: Optional[str] = None,
        timeout_ms: int = 500,
        attempts: int = 3,
    ) -> "Device":
        """A serial port (a board, or a pty of ``fricctl sim-device --pty``)
        or ``tcp="HOST:PORT"`` (the QEMU firmware, ``sim-device --tcp``)."""
    def __enter__(self) -> "Device": ...
    def __exit__(self, *args: Any) -> None: ...
    def close(self) -> None:
        """Closes the link (a virtual device ends)."""
    def info(self) -> Record:
        """``device info``: name, firmware, protocol, ranges, self-test."""
    def drive(
        self,
        *,
        freq: float,
        amp_z: float,
        amp_x: float,
        offset_z: float,
        phase_deg: float = 0.0,
        open_loop: bool = False,
        track: Literal["none", "z", "x"] = "none",
        headroom: Optional[float] = None,
    ) -> Record:
        """``device drive set`` (Hz, m, m, m, degrees): voltage mode with
        ``open_loop=True``, else the displacement mode (identified
        transducers) with resonance tracking and the headroom (1 … 8)."""
    def get_drive(self) -> Record:
        """``device drive get``."""
    def start(self) -> None:
        """``device start`` (soft start)."""
    def stop(self) -> None:
        """``device stop`` (ramped)."""
    def reset(self) -> None:
        """``device reset``: streams and measurements end, the drive stops."""
    def reset_faults(self) -> None:
        """``device reset-faults``."""
    def status(self) -> Record:
        """``device status`` (``running``, ``drive_mode``, ``faults`` by name,
        the measured drive, tracking, ``cpu_load_pct``, …)."""
    def scene(
        self, *, mu0: Optional[float] = None, kz: Optional[float] = None, kx: Optional[float] = None
    ) -> Record:
        """The device model's contact (μ0, N/m, N/m): set with all three,
        read with none (``device scene set|get``). ``kz`` and ``kx`` lie in
        [1, 1e12] N/m (ValueError naming the keyword otherwise)."""
    def predict(self, v0: float) -> Record:
        """``device predict``: the device model's μ at v0 (m/s)."""
    def measure(self, periods: int, *, wait: bool = True) -> Record:
        """``device measure``: μ over ``periods`` drive periods with the drive
        the pickups measured; an invalid estimate is returned (``valid`` is
        False), not raised."""
    def identify(
        self,
        *,
        from_hz: Optional[float] = None,
        to_hz: Optional[float] = None,
        points: int = 21,
        fine_points: int = 31,
        settle_ms: Optional[float] = None,
        channel: Literal["both", "z", "x"] = "both",
        store: bool = True,
    ) -> Record:
        """``device identify``: each transducer's f_r (Hz), Q, static gain
        (m/V) with 95 % intervals; stored on the device unless
        ``store=False``. The drive is put back afterwards."""
    def sweep(
        self,
        param: SweepParam,
        start: float,
        end: float,
        *,
        points: int,
        periods: int,
        v0: float,
        settle_periods: int = 0,
    ) -> Dict[str, Any]:
        """``device sweep``: ``param`` from ``start`` to ``end`` over ``points``
        (each measured over ``periods``, μ predicted at ``v0`` m/s); a dict
        of numpy arrays with the sweep file's columns (``value``,
        ``measured_mu``, ``std_error``, ``predicted_mu``, ``valid``, …),
        which :func:`fit` takes. The drive is put back afterwards."""
    def control(
        self,
        target_mu: Optional[float] = None,
        v0: Optional[float] = None,
        *,
        on: bool = True,
        gain: Optional[float] = None,
        periods: Optional[int] = None,
        rate: Optional[float] = None,
    ) -> Record:
        """``device control``: the closed μ loop on with the setpoint μ* at v0
        (m/s), or off with ``on=False``; the loop's state."""
    def watch(self, periods: int, *, count: Optional[int] = None) -> "Watch":
        """``device watch``: the device's stream of estimates of ``periods``
        periods, as an iterator of records (``count`` of them, or until the
        loop ends). The stream stops when the iterator ends, is closed or
        dropped, or raises (an error, a KeyboardInterrupt)."""

class Watch:
    """The iterator of :meth:`Device.watch`."""

    def __iter__(self) -> "Watch": ...
    def __next__(self) -> Record: ...
    def close(self) -> None:
        """Stops the stream now."""
