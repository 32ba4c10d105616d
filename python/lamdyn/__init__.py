"""lamdyn: the viscoelastic core of a laminated plate from its impact test.

The Rust library of the ``lamdyn`` command, with numpy arrays in and out. SI units
throughout (Hz, m, Pa, kg/m^3, K); FRF arrays are complex, indexed ``frf[response,
reference, line]``.

Stages, as in the command line:

- :func:`read_uff`, :func:`read_uff_functions`, :func:`write_uff`: universal files.
- :func:`ema`: modal identification (PolyMAX / LSCF, stabilization, LSFD).
- :func:`modes`: the lowest modes of a shell model (MITC4 or MITC9, optional edge layers).
- :func:`fit`, :func:`fit_job`: the laminate's effective modulus law E*(f) fitted to FRFs.
- :func:`core_inverse`: the core's G*(f) from E*(f), by the paper's and the exact inverse.
- :func:`run`: the whole chain on a job file (``lamdyn run``), report optional.
- :func:`write_demo_job`: the demo roof's simulated test as a job folder, at a temperature.
- :func:`master_curve`: one law and a WLF or Arrhenius shift over several temperatures.
- :mod:`lamdyn.batch`: many job files as Dask tasks.

Errors raise :class:`LamdynError` with lamdyn's message (the file, line or field at fault).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, fields, make_dataclass
from pathlib import Path
from typing import Any, Optional, Sequence, Union

import numpy as np

from lamdyn import _native
from lamdyn._native import LamdynError

__all__ = [
    "LamdynError",
    "FrfData",
    "version",
    "read_uff",
    "read_uff_functions",
    "write_uff",
    "ema",
    "EmaResult",
    "modes",
    "Modes",
    "fit",
    "fit_job",
    "FitResult",
    "core_inverse",
    "CoreInverse",
    "run",
    "RunResult",
    "ModalTable",
    "write_demo_job",
    "master_curve",
    "MasterCurve",
    "DEMO_WLF",
]

PathLike = Union[str, os.PathLike]

#: WLF constants of the demo core (:func:`write_demo_job`): C1, C2 in K, T_ref = 293.15 K
#: (20 degC, where the demo roof's core law is given). Values of the order published for PVB.
DEMO_WLF = {"c1": 12.0, "c2_k": 90.0, "reference_temperature_k": 293.15}


class _Fields:
    """Dict-style reading of a result's attributes (``r["modal"]`` is ``r.modal``), for code
    written against the dicts earlier versions returned."""

    def keys(self) -> list:
        return [f.name for f in fields(self)]

    def items(self) -> list:
        return [(k, getattr(self, k)) for k in self.keys()]

    def get(self, key: str, default: Any = None) -> Any:
        return getattr(self, key) if key in self.keys() else default

    def __getitem__(self, key: str) -> Any:
        if key not in self.keys():
            raise KeyError(key)
        return getattr(self, key)

    def __contains__(self, key: object) -> bool:
        return key in self.keys()


def version() -> str:
    """The version of the lamdyn crates the module was built from."""
    return _native.version()


@dataclass
class FrfData:
    """FRFs of responses x references on a frequency axis.

    Attributes:
        freqs_hz: frequency lines, Hz, shape (n_lines,).
        frf: complex FRFs, shape (n_responses, n_references, n_lines), in the unit of
            ``quantity`` (receptance m/N, mobility m/(s N), accelerance m/(s^2 N)).
        responses, references: one dict per channel: ``name``, ``point_m`` (x, y, z in m)
            and ``direction`` (unit vector).
        quantity: ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
        notices: what the reader skipped (datasets of kinds lamdyn does not read).
    """

    freqs_hz: np.ndarray
    frf: np.ndarray
    responses: list = field(default_factory=list)
    references: list = field(default_factory=list)
    quantity: str = "accelerance"
    notices: list = field(default_factory=list)


def _channels_json(channels: Optional[Sequence[Any]]) -> Optional[str]:
    if channels is None:
        return None
    out = []
    for c in channels:
        if isinstance(c, str):
            out.append({"name": c})
        else:
            out.append({k: (list(map(float, v)) if k != "name" else v) for k, v in dict(c).items()})
    return json.dumps(out)


def _f64(a: Any, name: str) -> np.ndarray:
    """``a`` as a contiguous 1-d float64 array; anything else raises LamdynError naming ``name``."""
    try:
        arr = np.ascontiguousarray(np.asarray(a, dtype=np.float64))
    except (TypeError, ValueError) as e:
        raise LamdynError(f"{name}: expected an array of real numbers: {e}") from None
    if arr.ndim != 1:
        raise LamdynError(f"{name}: expected a 1-d array, got shape {arr.shape}")
    return arr


def _frf(a: Any) -> np.ndarray:
    """FRFs as a contiguous complex128 array (responses, references, lines). A real array is
    refused: FRFs are complex, and a real one is most often magnitudes."""
    try:
        arr = np.asarray(a)
    except (TypeError, ValueError) as e:
        raise LamdynError(f"frf: expected an array of complex numbers: {e}") from None
    if not np.issubdtype(arr.dtype, np.complexfloating):
        raise LamdynError(
            f"frf: a {arr.dtype} array: FRFs are complex (magnitude and phase); pass the complex "
            "values, not magnitudes or real parts"
        )
    if arr.ndim == 2:  # one reference
        arr = arr[:, None, :]
    if arr.ndim != 3:
        raise LamdynError(
            f"frf: expected shape (responses, references, lines) or (responses, lines), got {arr.shape}"
        )
    return np.ascontiguousarray(arr, dtype=np.complex128)


def _complex(v: Any) -> Any:
    """num-complex's JSON ([re, im], or lists of them) as numpy complex."""
    a = np.asarray(v, dtype=np.float64)
    return a[..., 0] + 1j * a[..., 1]


def read_uff(path: PathLike, lenient: bool = False) -> FrfData:
    """The FRFs (datasets 58, function type 4) of a universal file as one :class:`FrfData`.

    ASCII and binary (58b) records are read; units come from dataset 164 and are converted to
    SI; the channels' positions from dataset 2411/15 (m). ``lenient`` accepts a record with
    fewer points than announced, or a 58b header whose byte count disagrees with its records
    (as pyuff 2.5.8 writes complex binary data), each with a notice.
    """
    freqs, frf, info = _native.read_uff(os.fspath(path), bool(lenient))
    info = json.loads(info)
    return FrfData(freqs, frf, info["responses"], info["references"], info["quantity"], info["notices"])


def read_uff_functions(path: PathLike, lenient: bool = False) -> list:
    """Every dataset 58 of a universal file as stored: one dict per record with the header
    fields (``function_type``, ``response_node``, ``response_direction``, ``reference_node``,
    ``reference_direction``, ``id_lines``, ...), ``x`` (the abscissa) and ``data`` (real or
    complex ordinates, in the file's units). ``lenient`` as in :func:`read_uff`."""
    out = []
    for header, x, data in _native.read_uff_functions(os.fspath(path), bool(lenient)):
        d = json.loads(header)
        d["x"] = x
        d["data"] = data
        out.append(d)
    return out


def write_uff(
    path: PathLike,
    freqs_hz: Any,
    frf: Any,
    responses: Optional[Sequence[Any]] = None,
    references: Optional[Sequence[Any]] = None,
    quantity: str = "accelerance",
    binary: bool = False,
) -> None:
    """Writes FRFs as a universal file: lamdyn's header (dataset 151), dataset 2411 (the
    channels' nodes, m), then one dataset 58 (or 58b when ``binary``) per response/reference
    pair, complex double, SI units.

    Channels are dicts (``name``, ``point_m``, ``direction``) or names; names like ``"12+Z"``
    give node 12, direction +Z.

    An existing file at ``path`` is replaced only when lamdyn wrote it (its 151 header names
    lamdyn), the rule of ``lamdyn run --out``: any other file raises :class:`LamdynError` and
    is left as it was.
    """
    _native.write_uff(
        os.fspath(path),
        _f64(freqs_hz, "freqs_hz"),
        _frf(frf),
        _channels_json(responses),
        _channels_json(references),
        quantity,
        bool(binary),
    )


def _typed(cls: type, values: dict) -> Any:
    """``cls`` from ``values``, which must hold its fields and nothing else: a key the Rust
    side added or dropped fails here (and in the tests) instead of vanishing."""
    names = {f.name for f in fields(cls)}
    if set(values) != names:
        raise LamdynError(
            f"internal: {cls.__name__} expects {sorted(names - set(values))} and got "
            f"{sorted(set(values) - names)} beyond its fields"
        )
    return cls(**values)


@dataclass
class EmaResult(_Fields):
    """What :func:`ema` identified: one entry per mode in each array.

    Attributes:
        freq_hz: natural frequencies |lambda|/2 pi, Hz.
        damping_ratio: viscous damping ratios -Re(lambda)/|lambda|.
        loss_factor: 2 x the damping ratio.
        poles: the poles lambda, complex, rad/s.
        shapes: complex shapes, modes x responses (mass-normalised with a driving point).
        mpc: modal phase collinearity (1 for a real mode).
        mpd_deg: mean phase deviation, degrees.
        freq_sd_hz, damping_sd: standard deviations from the fit's noise (NaN without
            refinement); they leave out the estimator's bias.
        verdict: per mode "sound", "doubtful" or "smear" (the reasons in
            ``modes[k]["quality"]``).
        second_shape_z, second_shape_rho: per mode the second-shape test (NaN where it has
            none): a second shape's energy under the pole over its chance level (1 for one
            mode), and its peak over the pole's (docs/ema.md, step 7).
        second_shape_calibrated: whether that test judged on these data.
        diagram_freq_hz, diagram_damping_ratio: the stabilization diagram's pole each mode
            started from, Hz and ratio.
        refined: whether the reported pole is the refined one (bool array).
        refined_freq_hz, refined_damping_ratio: the pole the refinement reached, taken or not
            (NaN without refinement).
        refinement: what became of it, per mode: "taken", "not better" (the check kept the
            diagram's), "left its column" or "beside a lost pole" (the diagram's put back), or
            "none".
        auto_mac: MAC of the shapes with each other, modes x modes.
        cmif: the CMIF, lines x singular values (in the data's units).
        modes: each mode in full as the CLI's result.json has it (list of dicts).
        diagram: the stabilization diagram's poles (list of dicts: order, pole, freq_hz,
            damping, stability).
        cmif_peaks: the first CMIF curve's peaks in the band (list of dicts: freq_hz, value).
        rejected: poles named by ``reject_hz`` (kept in the model, not structural modes).
        set_aside: modes set aside from a chain's inverses (empty here).
        band_hz: the band identified, Hz.
        correlation: FRAC of each regenerated curve against the measured one.
        curve_names: each curve's name, ``response@reference``.
        missing_hz: frequencies of ``near_hz`` without a stable pole within the window.
        warnings: what the identification warns of.
        timings: seconds per step (read, diagram, selection, refinement, check, residues,
            deviations, modes).
    """

    freq_hz: np.ndarray
    damping_ratio: np.ndarray
    loss_factor: np.ndarray
    poles: np.ndarray
    shapes: np.ndarray
    mpc: np.ndarray
    mpd_deg: np.ndarray
    freq_sd_hz: np.ndarray
    damping_sd: np.ndarray
    verdict: list
    second_shape_z: np.ndarray
    second_shape_rho: np.ndarray
    second_shape_calibrated: bool
    diagram_freq_hz: np.ndarray
    diagram_damping_ratio: np.ndarray
    refined: np.ndarray
    refined_freq_hz: np.ndarray
    refined_damping_ratio: np.ndarray
    refinement: list
    auto_mac: np.ndarray
    cmif: np.ndarray
    modes: list
    diagram: list
    cmif_peaks: list
    rejected: list
    set_aside: list
    band_hz: list
    correlation: list
    curve_names: list
    missing_hz: list
    warnings: list
    timings: dict


def _freq_and_damping(poles: np.ndarray) -> tuple:
    """|lambda|/2 pi (Hz) and -Re(lambda)/|lambda| of complex poles (rad/s); NaN stays NaN."""
    return np.abs(poles) / (2 * np.pi), -poles.real / np.maximum(np.abs(poles), 1e-300)


#: ``refinement`` labels of :func:`ema` by the outcome's name in the JSON.
_OUTCOMES = {"Taken": "taken", "NotBetter": "not better", "LeftItsColumn": "left its column",
             "BesideALostPole": "beside a lost pole"}


def ema(
    freqs_hz: Any,
    frf: Any,
    quantity: str = "accelerance",
    responses: Optional[Sequence[Any]] = None,
    references: Optional[Sequence[Any]] = None,
    band_hz: Optional[Sequence[float]] = None,
    orders: Sequence[int] = (2, 60, 2),
    near_hz: Optional[Sequence[float]] = None,
    reject_hz: Optional[Sequence[float]] = None,
    window_hz: float = 1.0,
    polymax: bool = True,
    refine: bool = True,
    driving: Union[str, int, None] = None,
    cmif_prominence: float = 2.0,
    poles: str = "rank-one",
) -> EmaResult:
    """Modal identification of FRFs, as ``lamdyn ema``.

    Poles by PolyMAX (several references) or LSCF over ``orders`` (lowest, highest, step; the
    default matches sdypy-EMA's ``pol_order_high=30``; ``polymax=False``: one LSCF over every
    curve, sdypy-EMA's formulation, better in f at isolated damped modes, worse in damping and
    blind to close pairs PolyMAX resolves: docs/ema.md, "Damped poles"), the stable columns of the
    stabilization diagram selected automatically (or the stable pole nearest each of
    ``near_hz``), then the poles' final estimate: by default (``poles="rank-one"``) with
    several responses the poles and participation factors fitted jointly with rank-one
    residues, beside the modes the selection left out that the curves need (docs/ema.md, "What
    the free residues cost at a close pair"; with one reference each fitted pole is then checked
    as ``"checked"`` checks the refined ones), and with one response as ``"checked"``: LSFD
    residues and a Levenberg-Marquardt refinement of the poles, each refined pole kept where it
    fits significantly better than the diagram's in the diagram's highest-order LSCF model;
    ``"refined"``: every refined pole; ``"diagram"`` or ``refine=False``: the diagram's poles.

    Returns an :class:`EmaResult` (its attributes also read as ``r["freq_hz"]``):
    ``freq_hz`` and ``damping_ratio`` arrays (one per mode), ``loss_factor``,
    ``poles`` (complex, rad/s), ``shapes`` (complex, modes x responses; each from the
    residues fitted within +-2 zeta f of its pole), ``mpc``,
    ``mpd_deg``, ``freq_sd_hz`` and ``damping_sd`` (standard deviations from the fit's noise,
    NaN without refinement), ``verdict`` (per mode: "sound", "doubtful" or "smear", the
    reasons in ``modes[k]["quality"]``), ``second_shape_z`` and ``second_shape_rho`` (the
    second-shape test, judging where ``second_shape_calibrated``), ``diagram_freq_hz`` and
    ``diagram_damping_ratio`` (the
    diagram's pole each mode started from) and ``refined`` (whether the reported pole is the
    refined one), ``refined_freq_hz`` and ``refined_damping_ratio`` (the pole the refinement
    reached, taken or not; NaN without refinement) and ``refinement`` (what became of it:
    "taken", "not better" — the check kept the diagram's —, "left its column" or "beside a
    lost pole" — the diagram's put back —, or "none"), ``auto_mac``, ``cmif`` (lines x
    singular values), and ``modes`` / ``diagram`` / ``cmif_peaks`` as lists of dicts (the CLI's
    result.json). The CMIF peaks listed are those whose topographic prominence in the band (as
    ``scipy.signal.find_peaks`` on log sigma_1) is at least the factor ``cmif_prominence``.
    ``driving`` names the driving-point response (mass-normalised shapes) as ``lamdyn ema
    --driving`` does, or gives its index.
    """
    if isinstance(driving, bool) or not (driving is None or isinstance(driving, (str, int, np.integer))):
        raise LamdynError(f"driving: a response's name or index, got {driving!r}")
    if isinstance(driving, np.integer):
        driving = int(driving)
    options = {
        "band_hz": None if band_hz is None else [float(b) for b in band_hz],
        "orders": [int(o) for o in orders],
        "near_hz": None if near_hz is None else [float(f) for f in near_hz],
        "reject_hz": None if reject_hz is None else [float(f) for f in reject_hz],
        "window_hz": float(window_hz),
        "polymax": bool(polymax),
        "refine": bool(refine),
        "estimator": poles,
        "driving": driving,
        "cmif_prominence": float(cmif_prominence),
    }
    r = json.loads(
        _native.ema(
            _f64(freqs_hz, "freqs_hz"),
            _frf(frf),
            _channels_json(responses),
            _channels_json(references),
            quantity,
            json.dumps(options),
        )
    )
    modes_ = r["modes"]
    r["freq_hz"] = np.array([m["freq_hz"] for m in modes_])
    r["damping_ratio"] = np.array([m["damping_ratio"] for m in modes_])
    r["loss_factor"] = np.array([m["loss_factor"] for m in modes_])
    r["poles"] = np.array([complex(*m["pole"]) for m in modes_])
    r["shapes"] = np.array([_complex(m["shape"]) for m in modes_]) if modes_ else np.zeros((0, 0), complex)
    r["mpc"] = np.array([m["mpc"] for m in modes_])
    r["mpd_deg"] = np.array([m["mpd_deg"] for m in modes_])
    sd = [m.get("sd") or {} for m in modes_]
    r["freq_sd_hz"] = np.array([d.get("freq_hz", np.nan) for d in sd])
    r["damping_sd"] = np.array([d.get("damping_ratio", np.nan) for d in sd])
    r["verdict"] = [m["quality"]["verdict"].lower() for m in modes_]
    tests = [m["quality"].get("second_shape") or {} for m in modes_]
    r["second_shape_z"] = np.array([t.get("statistic", np.nan) for t in tests])
    r["second_shape_rho"] = np.array([t.get("relative_amplitude", np.nan) for t in tests])
    r["second_shape_calibrated"] = bool(r.get("second_shape_calibrated", False))
    diagram_poles = np.array([complex(*m["diagram_pole"]) for m in modes_])
    r["diagram_freq_hz"], r["diagram_damping_ratio"] = _freq_and_damping(diagram_poles)
    r["refined"] = np.array([bool(m["refined"]) for m in modes_], dtype=bool)
    refinement = [m.get("refinement") for m in modes_]
    refined_poles = np.array([complex(*q["pole"]) if q else np.nan for q in refinement])
    r["refined_freq_hz"], r["refined_damping_ratio"] = _freq_and_damping(refined_poles)
    r["refinement"] = [_OUTCOMES[q["outcome"]] if q else "none" for q in refinement]
    r["auto_mac"] = np.array(r["auto_mac"])
    r["cmif"] = np.array(r["cmif"])
    return _typed(EmaResult, r)


def _model_json(model: Union[dict, PathLike]) -> tuple:
    """A model given as a dict (the layout of a ``lamdyn modes`` model TOML) or a TOML file."""
    if isinstance(model, dict):
        return json.dumps(model), "."
    path = Path(model)
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError as e:  # pragma: no cover
        raise LamdynError("reading a model TOML needs Python >= 3.11; pass the model as a dict") from e
    try:
        spec = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise LamdynError(f"cannot read '{path}': {e}") from e
    except tomllib.TOMLDecodeError as e:
        raise LamdynError(f"error in '{path}': {e}") from e
    return json.dumps(spec), os.fspath(path.parent)


@dataclass
class Modes(_Fields):
    """What :func:`modes` computed.

    Attributes:
        freqs_hz: natural frequencies, Hz (n_modes,).
        nodes: node coordinates, m (n_nodes, 3).
        shapes: mass-normalised shapes (n_modes, 6 n_nodes): per node u_x, u_y, u_z, m, and
            theta_x, theta_y, theta_z, rad (phi^T M phi = 1).
        rigid: whether each mode is a rigid-body mode (bool array).
        residual: each mode's relative eigen-residual |K phi - lambda M phi| / (|K| |phi|).
        elements: each element's node indices (list of lists).
    """

    freqs_hz: np.ndarray
    nodes: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    residual: np.ndarray
    elements: list


def modes(model: Union[dict, PathLike], n_modes: Optional[int] = None) -> Modes:
    """The lowest modes of a shell model (MITC4 or MITC9, Lanczos on the sparse Cholesky), as
    ``lamdyn modes``.

    ``model`` is a dict laid out as a model TOML (``mesh``, ``material``, ``solver``,
    ``supports``) or the path of one. Returns :class:`Modes`: ``freqs_hz`` (n_modes,), ``nodes`` (n_nodes, 3)
    in m, ``shapes`` (n_modes, 6 n_nodes), mass normalised (phi^T M phi = 1; per node
    u_x, u_y, u_z, theta_x, theta_y, theta_z), ``rigid`` (bool per mode) and ``residual``
    (relative eigen-residual per mode).
    """
    text, base = _model_json(model)
    if n_modes is not None:
        spec = json.loads(text)
        spec.setdefault("solver", {})["modes"] = int(n_modes)
        text = json.dumps(spec)
    freqs, nodes, shapes, info = _native.modes(text, base)
    info = json.loads(info)
    return Modes(
        freqs_hz=freqs,
        nodes=nodes,
        shapes=shapes,
        rigid=np.array(info["rigid"]),
        residual=np.array(info["residual"]),
        elements=info["elements"],
    )


@dataclass
class FitResult(_Fields):
    """What :func:`fit` and :func:`fit_job` found: the law E*(f) fitted to the FRFs.

    Attributes:
        freqs_hz: the measured lines, Hz.
        e_storage_pa, e_loss_factor: the fitted law's E' (Pa) and loss factor there.
        e_storage_sd_pa, e_loss_factor_sd: their standard deviations by the delta method
            through the parameters' covariance (NaN without one).
        parameters: each law parameter by name: a dict with its value, sd and 95 % interval.
        peaks_hz: the measured resonances the fit read, Hz.
        result: the whole fit as the CLI's JSON has it (starts, peaks, convergence).
        source: where the data came from.
        model_line: the model, in a line.
        notes: what the fit notes of its inputs.
    """

    freqs_hz: np.ndarray
    e_storage_pa: np.ndarray
    e_loss_factor: np.ndarray
    e_storage_sd_pa: np.ndarray
    e_loss_factor_sd: np.ndarray
    parameters: dict
    peaks_hz: np.ndarray
    result: dict
    source: str
    model_line: str
    notes: list


def _fit_out(text: str) -> FitResult:
    r = json.loads(text)
    for k in ("freqs_hz", "e_storage_pa", "e_loss_factor", "e_storage_sd_pa", "e_loss_factor_sd"):
        r[k] = np.array([np.nan if v is None else v for v in r[k]], dtype=float)
    r["parameters"] = {p["name"]: p for p in r["result"]["parameters"]}
    r["peaks_hz"] = np.array([p["freq_hz"] for p in r["result"]["peaks"]])
    return _typed(FitResult, r)


def fit_job(job: PathLike) -> FitResult:
    """``lamdyn fit JOB``: the job's measurement, model and ``[fit]`` settings; returns the
    fitted law (``parameters`` by name with value, sd and 95 % interval), ``result`` (the
    CLI's full result), and E'(f) (Pa), eta(f) with standard deviations on the measured
    lines."""
    return _fit_out(_native.fit_job(os.fspath(job)))


def fit(
    freqs_hz: Any,
    frf: Any,
    responses: Sequence[Any],
    references: Sequence[Any],
    model: Union[dict, PathLike],
    quantity: str = "accelerance",
    law: str = "per_mode",
    band_hz: Optional[Sequence[float]] = None,
    misfit: str = "log_rms",
    reference: int = 0,
    exclude_hz: Optional[Sequence[Sequence[float]]] = None,
    covariance: str = "robust_hc3",
    n_modes: Optional[int] = None,
    residual: bool = True,
    tolerance_m: float = 1e-3,
    sensor_mapping: str = "surface",
) -> FitResult:
    """The effective modulus law E*(f) of the laminate fitted to FRF arrays (paper eqs. 2-10):
    the shell ``model`` (free, E_ref in its material) scaled by the law, modes projected on the
    channels (each placed within ``tolerance_m``, m, on the nearest point of the mid-surface and
    interpolated there with the element's shape functions, or with
    ``sensor_mapping="nearest_node"`` on the nearest node), compared with the
    measurement over ``band_hz`` by ``misfit`` (``rms``, ``log_rms`` or ``complex``) for
    reference ``reference``. ``law`` is ``paper_eq7``, ``fractional_zener`` or ``per_mode``.

    Returns as :func:`fit_job`.
    """
    text, base = _model_json(model)
    spec = {"kind": misfit, "reference": int(reference)}
    if band_hz is not None:
        spec["band_hz"] = [float(b) for b in band_hz]
    if exclude_hz is not None:
        spec["exclude_hz"] = [[float(a), float(b)] for a, b in exclude_hz]
    options = {
        "law": law,
        "misfit": spec,
        "covariance": covariance,
        "modes": n_modes,
        "residual": bool(residual),
        "tolerance_m": float(tolerance_m),
        "sensor_mapping": sensor_mapping,
    }
    return _fit_out(
        _native.fit_frf(
            _f64(freqs_hz, "freqs_hz"),
            _frf(frf),
            _channels_json(responses),
            _channels_json(references),
            quantity,
            text,
            base,
            json.dumps(options),
        )
    )


def _stack_json(stack: Union[dict, PathLike]) -> str:
    if isinstance(stack, dict):
        return json.dumps(stack)
    import tomllib

    path = Path(stack)
    try:
        return json.dumps(tomllib.loads(path.read_text(encoding="utf-8")))
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise LamdynError(f"cannot read the stack '{path}': {e}") from e


@dataclass
class CoreInverse(_Fields):
    """What :func:`core_inverse` found at each line (NaN where an inverse has no solution).

    Attributes:
        paper_storage_pa, paper_loss_factor: the core's G' (Pa) and eta by the paper's inverse
            (eqs. 33-45).
        paper_phi_abs: |phi| of the paper's inverse (eq. 37; above 0.1 beyond its ~1 %
            validity).
        paper_error: why the paper's inverse has no solution at a line (None where it has).
        exact_storage_pa, exact_loss_factor: by the exact Mead-Markus inverse.
        exact_error: why the exact inverse has none (None where it has).
    """

    paper_storage_pa: np.ndarray
    paper_loss_factor: np.ndarray
    paper_phi_abs: np.ndarray
    paper_error: list
    exact_storage_pa: np.ndarray
    exact_loss_factor: np.ndarray
    exact_error: list


def core_inverse(
    freqs_hz: Any,
    e_storage_pa: Any,
    e_loss_factor: Any,
    stack: Union[dict, PathLike],
    kinematics: str = "beam",
    core_formula: str = "eq41",
    face_shear: str = "neglect",
    bending: str = "faces",
) -> CoreInverse:
    """The core's G*(f) from the laminate's effective E*(f) (``lamdyn core``, same defaults):
    by the paper's inverse (eqs. 33-45: ``core_formula`` eq41, eq43 or eq26; ``face_shear``
    neglect (eq. 40) or include (eq. 39); ``bending`` faces (eq. 35) or full (eq. 14)) and by
    the exact Mead-Markus inverse. ``stack`` is a dict laid out as a stack TOML (``layers``:
    faces with ``young_pa``, the core without a modulus) or its path; ``kinematics``
    ``beam`` (the paper's equations per unit width) or ``plate`` (cylindrical bending, as
    ``lamdyn run``).

    Returns arrays (NaN where an inverse has no solution, with the reason in ``*_error``):
    ``paper_storage_pa``, ``paper_loss_factor``, ``paper_phi_abs`` (|phi|, eq. 37),
    ``exact_storage_pa``, ``exact_loss_factor``.
    """
    r = json.loads(
        _native.core_inverse(
            _f64(freqs_hz, "freqs_hz"),
            _f64(e_storage_pa, "e_storage_pa"),
            _f64(e_loss_factor, "e_loss_factor"),
            _stack_json(stack),
            kinematics,
            core_formula,
            face_shear,
            bending,
        )
    )
    for k, v in list(r.items()):
        if not k.endswith("_error"):
            r[k] = np.array([np.nan if x is None else x for x in v], dtype=float)
    return _typed(CoreInverse, r)


def _modal_table_class() -> type:
    """``ModalTable`` made from the core table's one definition (``lamdyn_pipeline``'s
    ``report::core_table``, the columns of ``core_modal.csv`` and of ``lamdyn run``'s summary)."""
    columns = json.loads(_native.core_columns())
    lines = [
        "The core found at each modal frequency of a run: one attribute per column of",
        "``core_modal.csv``, all of the same length. Numbers are float arrays in SI units (NaN",
        "where a route has no value, or where the run has no truth or no FRF fit); texts are",
        "lists of str (\"\" where none).",
        "",
        "Attributes:",
    ]
    for c in columns:
        unit = f", {c['unit']}" if c["unit"] else ""
        lines.append(f"    {c['key']}: {c['about']}{unit}.")
    cls = make_dataclass(
        "ModalTable",
        [(c["key"], list if c["text"] else np.ndarray) for c in columns],
        bases=(_Fields,),
    )
    cls.__doc__ = "\n".join(lines)
    cls.__module__ = __name__
    cls._text_columns = frozenset(c["key"] for c in columns if c["text"])
    return cls


ModalTable = _modal_table_class()


@dataclass
class RunResult(_Fields):
    """What :func:`run` found on a job.

    Attributes:
        title: the job's title.
        job: the job file's path.
        temperature_k: the test's temperature, K (None when the job states none).
        modal: the core at each modal frequency (:class:`ModalTable`).
        ema_modes: the identified modes as (frequency in Hz, damping ratio) pairs.
        ema_freq_hz, ema_damping_ratio: the same as arrays.
        modes_without_core: frequencies (Hz) where no inverse found a core.
        warnings: the run's warnings, as the report lists them.
        timings: (stage, seconds, from the cache) per stage.
        report: the report's folder, when one was written.
    """

    title: str
    job: str
    temperature_k: Optional[float]
    modal: ModalTable
    ema_modes: list
    ema_freq_hz: np.ndarray
    ema_damping_ratio: np.ndarray
    modes_without_core: list
    warnings: list
    timings: list
    report: Optional[str]


def _run_out(text: str) -> RunResult:
    r = json.loads(text)
    columns = r["modal"]
    modal = ModalTable(
        **{
            f.name: (
                ["" if v is None else v for v in columns[f.name]]
                if f.name in ModalTable._text_columns
                else np.array([np.nan if v is None else v for v in columns[f.name]], dtype=float)
            )
            for f in fields(ModalTable)
        }
    )
    return RunResult(
        title=r["title"],
        job=r["job"],
        temperature_k=r["temperature_k"],
        modal=modal,
        ema_modes=[tuple(m) for m in r["ema_modes"]],
        ema_freq_hz=np.array([m[0] for m in r["ema_modes"]]),
        ema_damping_ratio=np.array([m[1] for m in r["ema_modes"]]),
        modes_without_core=r["modes_without_core"],
        warnings=r["warnings"],
        timings=[tuple(t) for t in r["timings"]],
        report=r["report"],
    )


def run(
    job: PathLike,
    out: Optional[PathLike] = None,
    cache: Union[PathLike, None, str] = "beside",
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    force: bool = False,
) -> RunResult:
    """``lamdyn run JOB``: the whole chain on a job file.

    The report (HTML, figures, CSV/JSON tables) is written to ``out`` when given, under the
    CLI's folder rules (only files lamdyn wrote are replaced; a folder holding other files or
    the inputs is refused unless ``force``). ``cache`` is the cache folder: ``"beside"`` (the
    default, ``.lamdyn-cache`` next to the job, as the CLI), a path, or None (no cache).
    ``samples``/``seed`` override the job's Monte Carlo.

    Returns a :class:`RunResult`: ``modal`` (a :class:`ModalTable`, arrays per column at the
    modal frequencies: E', eta of the laminate, |phi|, G' and eta of the core by the paper's,
    the exact and the layered inverse, and the truth when the job names one),
    ``temperature_k``, the EMA's modes, ``modes_without_core``, ``warnings``, ``timings``,
    ``report``.
    """
    job = Path(job)
    if cache == "beside":
        cache = job.parent / ".lamdyn-cache"
    return _run_out(
        _native.run(
            os.fspath(job),
            None if out is None else os.fspath(out),
            None if cache is None else os.fspath(cache),
            samples,
            seed,
            bool(force),
        )
    )


def write_demo_job(
    out: PathLike,
    temperature_k: Optional[float] = None,
    c1: float = DEMO_WLF["c1"],
    c2_k: float = DEMO_WLF["c2_k"],
    samples: int = 0,
    seed: int = 1,
    force: bool = False,
) -> str:
    """Simulates the demo roof's impact test (``lamdyn demo``'s virtual test: five hammer hits
    on the free laminated roof, 243 channels) and writes it as a job folder ``out``; returns
    the path of ``job.toml``.

    With ``temperature_k`` the core's law (given at 293.15 K) is moved to that temperature by
    a WLF shift with ``c1`` and ``c2_k`` (K), and the job states its ``temperature_k``: the
    virtual tests of a master curve. ``samples`` is the job's Monte Carlo size (0: none).
    """
    return _native.write_demo_job(
        os.fspath(out),
        None if temperature_k is None else float(temperature_k),
        float(c1),
        float(c2_k),
        int(samples),
        int(seed),
        bool(force),
    )


@dataclass
class MasterCurve(_Fields):
    """One core law and its temperature shift over several temperatures (:func:`master_curve`).

    Attributes:
        parameters: by name (the law's ``g0_pa``, ``g_inf_pa``, ``tau_s``, ``alpha``; the
            shift's ``c1`` and ``c2_k``, or ``activation_energy_j_mol``): a dict with
            ``value``, ``sd`` and the 95 % profile-likelihood interval ``ci95`` (infinite on a
            side the data do not bound).
        undetermined: parameter combinations the data do not fix.
        correlation: the parameters' correlation matrix.
        residual_sd: the relative scatter of G' and of eta about the curve.
        points: the points fitted.
        t95: Student's t for the 95 % intervals.
        shift: ``"wlf"`` or ``"arrhenius"``.
        reference_temperature_k: where a_T = 1, K.
        shift_factors: log10 a_T with its 95 % band at each temperature of the data.
        reduced_freq_hz: the curve's reduced frequencies, Hz.
        storage_pa, storage_ci95: G' on the curve, Pa, and its 95 % band (2 x n).
        loss_factor, loss_factor_ci95: eta on the curve and its 95 % band (2 x n).
        temperatures_k, log10_a_t, log10_a_t_ci95: the shift over temperature, K, with its
            95 % band (2 x n).
    """

    parameters: dict
    undetermined: list
    correlation: np.ndarray
    residual_sd: Any
    points: Any
    t95: float
    shift: str
    reference_temperature_k: float
    shift_factors: list
    reduced_freq_hz: np.ndarray
    storage_pa: np.ndarray
    storage_ci95: np.ndarray
    loss_factor: np.ndarray
    loss_factor_ci95: np.ndarray
    temperatures_k: np.ndarray
    log10_a_t: np.ndarray
    log10_a_t_ci95: np.ndarray


def master_curve(
    results: Optional[Sequence[Union[RunResult, dict]]] = None,
    *,
    temperature_k: Any = None,
    freq_hz: Any = None,
    storage_pa: Any = None,
    loss_factor: Any = None,
    reference_temperature_k: float = 293.15,
    shift: str = "wlf",
    inverse: str = "layered",
    curve_freqs_hz: Any = None,
    curve_temperatures_k: Any = None,
) -> MasterCurve:
    """One core law and its temperature shift fitted to cores identified at several
    temperatures (time-temperature superposition): G*(f; T) = G*_ref(a_T f), with a
    fractional Zener G*_ref and a_T by WLF (``shift="wlf"``: C1, C2 in K) or Arrhenius
    (``"arrhenius"``: activation energy in J/mol), a_T = 1 at ``reference_temperature_k``.

    The points come from ``results`` (:class:`RunResult` s of :func:`run` or of
    :func:`lamdyn.batch.run_batch`, or dicts laid out alike, each with its ``temperature_k``; the ``inverse``'s core:
    ``layered``, ``exact`` or ``paper``) or from the arrays ``temperature_k``, ``freq_hz``,
    ``storage_pa`` and ``loss_factor``.

    Returns a :class:`MasterCurve`; its curve is at ``curve_freqs_hz`` (reduced, Hz; default 60
    points over the data's reduced band) and its shift at ``curve_temperatures_k`` (default:
    40 points over the data's temperatures).
    """
    if results is not None:
        t, f, g, eta = [], [], [], []
        for r in results:
            if r.get("temperature_k") is None:
                raise LamdynError(f"result of '{r.get('job')}' has no temperature_k: state it in the job")
            m = r["modal"]
            s, e = m[f"g_{inverse}_storage_pa"], m[f"g_{inverse}_loss_factor"]
            ok = np.isfinite(s) & np.isfinite(e) & (s > 0) & (e > 0)
            t.extend([r["temperature_k"]] * int(ok.sum()))
            f.extend(m["f_hz"][ok])
            g.extend(s[ok])
            eta.extend(e[ok])
        temperature_k, freq_hz, storage_pa, loss_factor = t, f, g, eta
    t = _f64(temperature_k, "temperature_k")
    f = _f64(freq_hz, "freq_hz")
    if curve_temperatures_k is None:
        curve_temperatures_k = np.linspace(t.min(), t.max(), 40) if t.size else np.zeros(0)
    fixed_curve = curve_freqs_hz is not None
    text = _native.master_curve(
        t,
        f,
        _f64(storage_pa, "storage_pa"),
        _f64(loss_factor, "loss_factor"),
        float(reference_temperature_k),
        shift,
        _f64(curve_freqs_hz if fixed_curve else [], "curve_freqs_hz"),
        _f64(curve_temperatures_k, "curve_temperatures_k"),
    )
    r = json.loads(text)
    fit_ = r["fit"]
    if not fixed_curve:
        # The data's reduced band, then the curve on it.
        log_a = {round(p["temperature_k"], 9): p["log10_a_t"] for p in fit_["shift_factors"]}
        reduced = f * 10 ** np.array([log_a[round(x, 9)] for x in t])
        grid = np.geomspace(reduced.min(), reduced.max(), 60)
        r = json.loads(
            _native.master_curve(
                t,
                f,
                _f64(storage_pa, "storage_pa"),
                _f64(loss_factor, "loss_factor"),
                float(reference_temperature_k),
                shift,
                grid,
                _f64(curve_temperatures_k, "curve_temperatures_k"),
            )
        )
        fit_ = r["fit"]
    for p in fit_["parameters"]:
        # JSON has no infinity: an open side of an interval comes as null.
        lo, hi = p["ci95"]
        p["ci95"] = [-np.inf if lo is None else lo, np.inf if hi is None else hi]
    c, sc = r["curve"], r["shift_curve"]
    band = lambda rows, k: np.array([p[k] for p in rows]).T.reshape(2, -1)  # noqa: E731
    return MasterCurve(
        parameters={p["name"]: p for p in fit_["parameters"]},
        undetermined=fit_["undetermined"],
        correlation=np.array(fit_["correlation"]),
        residual_sd=fit_["residual_sd"],
        points=fit_["points"],
        t95=fit_["t95"],
        shift=fit_["shift"],
        reference_temperature_k=fit_["reference_temperature_k"],
        shift_factors=fit_["shift_factors"],
        reduced_freq_hz=np.array([p["reduced_freq_hz"] for p in c]),
        storage_pa=np.array([p["storage_pa"] for p in c]),
        storage_ci95=band(c, "storage_ci95"),
        loss_factor=np.array([p["loss_factor"] for p in c]),
        loss_factor_ci95=band(c, "loss_factor_ci95"),
        temperatures_k=np.array([p["temperature_k"] for p in sc]),
        log10_a_t=np.array([p["log10_a_t"] for p in sc]),
        log10_a_t_ci95=band(sc, "log10_a_t_ci95"),
    )
