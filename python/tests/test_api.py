"""The package's public names and their signatures, pinned: a rename, a removed name or a
changed parameter fails here, and an intended change updates this table with a note for
users (docs/python.md)."""

import inspect

import pytest

import lamdyn
import lamdyn.batch

#: Each public function's signature as ``inspect.signature`` prints it; ``None`` for a class
#: or a constant.
PUBLIC = {
    'LamdynError': None,
    'FrfData': None,
    'version': "() -> 'str'",
    'read_uff': "(path: 'PathLike', lenient: 'bool' = False) -> 'FrfData'",
    'read_uff_functions': "(path: 'PathLike', lenient: 'bool' = False) -> 'list'",
    'write_uff': "(path: 'PathLike', freqs_hz: 'Any', frf: 'Any', responses: 'Optional[Sequence[Any]]' = None, references: 'Optional[Sequence[Any]]' = None, quantity: 'str' = 'accelerance', binary: 'bool' = False) -> 'None'",
    'ema': "(freqs_hz: 'Any', frf: 'Any', quantity: 'str' = 'accelerance', responses: 'Optional[Sequence[Any]]' = None, references: 'Optional[Sequence[Any]]' = None, band_hz: 'Optional[Sequence[float]]' = None, orders: 'Sequence[int]' = (2, 60, 2), near_hz: 'Optional[Sequence[float]]' = None, reject_hz: 'Optional[Sequence[float]]' = None, window_hz: 'float' = 1.0, polymax: 'bool' = True, refine: 'bool' = True, driving: 'Union[str, int, None]' = None, cmif_prominence: 'float' = 2.0, poles: 'str' = 'rank-one') -> 'EmaResult'",
    'EmaResult': None,
    'modes': "(model: 'Union[dict, PathLike]', n_modes: 'Optional[int]' = None) -> 'Modes'",
    'Modes': None,
    'fit': "(freqs_hz: 'Any', frf: 'Any', responses: 'Sequence[Any]', references: 'Sequence[Any]', model: 'Union[dict, PathLike]', quantity: 'str' = 'accelerance', law: 'str' = 'per_mode', band_hz: 'Optional[Sequence[float]]' = None, misfit: 'str' = 'log_rms', reference: 'int' = 0, exclude_hz: 'Optional[Sequence[Sequence[float]]]' = None, covariance: 'str' = 'robust_hc3', n_modes: 'Optional[int]' = None, residual: 'bool' = True, tolerance_m: 'float' = 0.001, sensor_mapping: 'str' = 'surface') -> 'FitResult'",
    'fit_job': "(job: 'PathLike') -> 'FitResult'",
    'FitResult': None,
    'core_inverse': "(freqs_hz: 'Any', e_storage_pa: 'Any', e_loss_factor: 'Any', stack: 'Union[dict, PathLike]', kinematics: 'str' = 'beam', core_formula: 'str' = 'eq41', face_shear: 'str' = 'neglect', bending: 'str' = 'faces') -> 'CoreInverse'",
    'CoreInverse': None,
    'run': "(job: 'PathLike', out: 'Optional[PathLike]' = None, cache: 'Union[PathLike, None, str]' = 'beside', samples: 'Optional[int]' = None, seed: 'Optional[int]' = None, force: 'bool' = False) -> 'RunResult'",
    'RunResult': None,
    'ModalTable': None,
    'write_demo_job': "(out: 'PathLike', temperature_k: 'Optional[float]' = None, c1: 'float' = 12.0, c2_k: 'float' = 90.0, samples: 'int' = 0, seed: 'int' = 1, force: 'bool' = False) -> 'str'",
    'master_curve': "(results: 'Optional[Sequence[Union[RunResult, dict]]]' = None, *, temperature_k: 'Any' = None, freq_hz: 'Any' = None, storage_pa: 'Any' = None, loss_factor: 'Any' = None, reference_temperature_k: 'float' = 293.15, shift: 'str' = 'wlf', inverse: 'str' = 'layered', curve_freqs_hz: 'Any' = None, curve_temperatures_k: 'Any' = None) -> 'MasterCurve'",
    'MasterCurve': None,
    'DEMO_WLF': None,
}

#: The same for :mod:`lamdyn.batch`.
BATCH = {
    'BatchResult': None,
    'run_batch': "(jobs: 'Sequence[PathLike]', *, out: 'Optional[PathLike]' = None, cache: 'Union[PathLike, None, str]' = 'shared', client: 'Any' = None, address: 'Optional[str]' = None, n_workers: 'int' = 2, samples: 'Optional[int]' = None, seed: 'Optional[int]' = None, force: 'bool' = False, progress: 'Union[bool, Callable[[str], None]]' = True) -> 'BatchResult'",
    'job_names': "(jobs: 'Sequence[PathLike]') -> 'list'",
}


def check(module, table):
    assert sorted(module.__all__) == sorted(table), "public names changed"
    for name, want in table.items():
        obj = getattr(module, name)
        if want is None:
            assert not inspect.isfunction(obj), name
        else:
            assert str(inspect.signature(obj)) == want, name
            assert obj.__doc__, f"{name} has no docstring"


def test_the_package_s_public_names_and_signatures_are_pinned():
    check(lamdyn, PUBLIC)


def test_the_batch_module_s_public_names_and_signatures_are_pinned():
    check(lamdyn.batch, BATCH)



def test_results_are_typed_and_still_read_as_dicts():
    """A run's and a master curve's results are dataclasses with attributes; ``r["modal"]`` and
    ``r.get("temperature_k")`` read the same attributes for code written against dicts."""
    import dataclasses

    import numpy as np

    table = lamdyn.ModalTable(**{f.name: np.zeros(2) for f in dataclasses.fields(lamdyn.ModalTable)})
    r = lamdyn.RunResult("t", "job.toml", 293.15, table, [], np.zeros(0), np.zeros(0), [], [], [], None)
    assert r["modal"] is r.modal and r.get("temperature_k") == 293.15 and "modal" in r
    assert r.get("nothing", 1) == 1
    assert [k for k, _ in r.modal.items()][:2] == ["f_hz", "e_storage_pa"]
    try:
        r["nothing"]
    except KeyError:
        pass
    else:
        raise AssertionError("an unknown key must raise KeyError")
    for cls in (lamdyn.RunResult, lamdyn.ModalTable, lamdyn.MasterCurve, lamdyn.EmaResult,
                lamdyn.Modes, lamdyn.FitResult, lamdyn.CoreInverse):
        assert dataclasses.is_dataclass(cls) and cls.__doc__ and "Attributes:" in cls.__doc__



def test_errors_pickle_and_keep_their_class_across_processes(tmp_path):
    """A LamdynError keeps its class and message through pickle and from a Dask worker's
    process (a file that does not exist, read there), so a batch's caller can catch it by
    class."""
    import pickle

    from distributed import Client, LocalCluster

    e = pickle.loads(pickle.dumps(lamdyn.LamdynError("stack.layers[1]: bad")))
    assert type(e) is lamdyn.LamdynError and str(e) == "stack.layers[1]: bad"
    assert lamdyn.LamdynError.__module__ == "lamdyn"
    missing = str(tmp_path / "missing.uff")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        future = client.submit(lamdyn.read_uff, missing, pure=False)
        try:
            future.result()
        except lamdyn.LamdynError as got:
            assert "missing.uff" in str(got)
        else:
            raise AssertionError("no error came back")


def test_refusals_name_python_s_arguments(tmp_path, temperature_jobs):
    """A results folder holding a user's file is refused in Python's words (``force=True``,
    ``out``), not with the CLI's flags."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    calls = (
        lambda: lamdyn.write_demo_job(out),
        lambda: lamdyn.run(temperature_jobs[0], out=out, cache=None),
    )
    for call in calls:
        with pytest.raises(lamdyn.LamdynError, match="did not write") as refusal:
            call()
        assert "force=True" in str(refusal.value) and "--" not in str(refusal.value), refusal.value
    assert (out / "notes.txt").read_text() == "mine"


def test_bad_arrays_raise_lamdyns_error_naming_the_argument():
    """Real-valued FRFs (magnitudes, most often) are refused; arrays that are not numbers, or of
    the wrong shape, raise LamdynError naming the argument, not numpy's ValueError."""
    import numpy as np

    f = np.linspace(1, 100, 200)
    h = 1 / (1 - (f / 50) ** 2 + 0.02j)
    with pytest.raises(lamdyn.LamdynError, match=r"^frf: a float64 array: FRFs are complex"):
        lamdyn.ema(f, np.abs(h)[None, :])
    with pytest.raises(lamdyn.LamdynError, match=r"^freqs_hz: expected an array of real numbers"):
        lamdyn.ema(["one", "two"], h[None, :])
    with pytest.raises(lamdyn.LamdynError, match=r"^freqs_hz: expected a 1-d array"):
        lamdyn.ema(f[None, :], h[None, :])
    with pytest.raises(lamdyn.LamdynError, match=r"^e_storage_pa: expected an array of real numbers"):
        lamdyn.core_inverse([100.0], [1e9 + 1j], [0.1], stack={})


def test_the_driving_point_is_named_as_the_cli_names_it():
    """``driving`` takes the response's name (as ``lamdyn ema --driving``) or its index, with
    the same shapes either way; a name that is not a response lists the responses."""
    import numpy as np

    f = np.linspace(1, 100, 400)
    h1 = 1 / (1 - (f / 30) ** 2 + 0.04j * f / 30) + 0.5 / (1 - (f / 70) ** 2 + 0.04j * f / 70)
    h2 = 0.7 / (1 - (f / 30) ** 2 + 0.04j * f / 30) - 0.4 / (1 - (f / 70) ** 2 + 0.04j * f / 70)
    frf = np.array([h1, h2])
    names = ["1+Z", "2+Z"]
    by_name = lamdyn.ema(f, frf, responses=names, driving="2+Z", band_hz=(10, 90))
    by_index = lamdyn.ema(f, frf, responses=names, driving=1, band_hz=(10, 90))
    np.testing.assert_array_equal(by_name["shapes"], by_index["shapes"])
    with pytest.raises(lamdyn.LamdynError, match=r"driving: '3\+Z' is not a response of the data \(2 responses: 1\+Z, 2\+Z\)"):
        lamdyn.ema(f, frf, responses=names, driving="3+Z", band_hz=(10, 90))
    with pytest.raises(lamdyn.LamdynError, match="driving: index 5 is not a response"):
        lamdyn.ema(f, frf, responses=names, driving=5, band_hz=(10, 90))
