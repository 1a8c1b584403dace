"""Bad ``--config`` options (found by the slow random-damage test: a flipped byte turned a
key into an unknown one, and the error did not say which file). Every runner refuses an
unknown key and a value of the wrong type with exit status 2 and one line naming the
config file and the key; never a traceback of a ``float('x')``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from dbn.errors import ConfigError
from models.cli import main
from models.jorge.strokes import StrokeConfig
from models.track.options import array, build, check_keys, flag, integer, number, override, text

DATA = Path(__file__).resolve().parents[1] / "data"
LOC = ["localization/odometry.csv", "localization/measurements.csv",
       "localization/landmarks.csv", "localization/groundtruth.csv"]  # fmt: skip
#: runner -> (inputs under tests/data, a known key and a value of the wrong type)
RUNNERS = {
    "localization": (LOC, "dt", "x"),
    "jorge": (["jorge/caviar.xml"], "gap_min", "five"),
    "pathrecovery": (["pathrecovery/edges.csv", "pathrecovery/observations.csv"],
                     "num_particles", "many"),
    "rjmcmc3d": (["rjmcmc3d/view0"], "sigma_px", [4]),
    "zajdel_adf": (["zajdel/observations.csv"], "within_std", "wide"),
    "zajdel_learnsearch": (["zajdel/observations.csv"], "window", {"a": 1}),
    "dbn": (["dbn/umbrella.bif", "dbn/evidence.csv"], "num_particles", 100),
}


def _run(capsys, tmp_path: Path, name: str, config: dict) -> tuple[int, str]:
    inputs, _, _ = RUNNERS[name]
    path = tmp_path / "opts.json"
    path.write_text(json.dumps(config))
    argv = ["track", name, *[str(DATA / p) for p in inputs], "--config", str(path),
            "-o", str(tmp_path / "out"), "--quiet"]  # fmt: skip
    rc = main(argv)
    return rc, capsys.readouterr().err.strip()


@pytest.mark.parametrize("name", sorted(RUNNERS))
def test_unknown_key_names_the_config_file(capsys, tmp_path, name):
    rc, err = _run(capsys, tmp_path, name, {"bogus_key": 1})
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "opts.json" in err and "bogus_key" in err, err


@pytest.mark.parametrize("name", sorted(RUNNERS))
def test_wrong_type_names_the_config_file_and_key(capsys, tmp_path, name):
    _, key, bad = RUNNERS[name]
    rc, err = _run(capsys, tmp_path, name, {key: bad})
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "opts.json" in err and key in err, err
    assert "Traceback" not in err


def test_localization_odometry_shorter_than_a_step_names_the_file(capsys, tmp_path):
    """A truncated odometry (two rows, 0.05 s): the error names the odometry file, not
    the derived duration alone."""
    lines = (DATA / LOC[0]).read_text().splitlines()
    short = tmp_path / "odometry.csv"
    short.write_text("\n".join(lines[:3]) + "\n")
    argv = ["track", "localization", str(short), *[str(DATA / p) for p in LOC[1:]],
            "-o", str(tmp_path / "out"), "--quiet"]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "odometry.csv" in err and "one step" in err, err


@pytest.mark.parametrize("config, key", [({"duration": 200.0}, "duration"),  # 8 s of data
                                         ({"start": 99.0}, "start"),  # before the first time
                                         ({"start": 107.99}, "start")])  # after the last
def test_localization_span_outside_the_odometry_names_the_file(capsys, tmp_path, config, key):
    """A run past the odometry's end, or starting outside it, is refused naming the
    odometry file and the key (the dead reckoning held the last pose: steps of no data)."""
    rc, err = _run(capsys, tmp_path, "localization", config)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "odometry.csv" in err and f"config {key}" in err, err


@pytest.mark.parametrize("bad", [{}, [], False, "", 0])
def test_localization_duration_of_the_wrong_kind_is_refused(capsys, tmp_path, bad):
    """``duration`` is a number of seconds or absent (null: the whole odometry); an empty
    object, list or string, ``false`` and 0 used to read as absent and ran the whole file."""
    rc, err = _run(capsys, tmp_path, "localization", {"duration": bad})
    assert rc == 2 and len(err.splitlines()) == 1 and "duration" in err, err


#: values a random sweep of every runner's keys found unchecked (a raw ZeroDivisionError,
#: OverflowError, numpy shape error, an endless growth loop, or a key silently ignored)
RANGE_CASES = [
    ("zajdel_adf", {"init_persons": 0}, "init_persons"),  # grew its capacity forever
    ("zajdel_adf", {"init_persons": -1}, "init_persons"),
    ("zajdel_adf", {"mix_top": 0}, "mix_top"),
    ("zajdel_adf", {"prune_eps": 1.5}, "prune_eps"),
    ("zajdel_adf", {"num_borders": 0}, "num_borders"),
    ("zajdel_adf", {"num_cameras": -1}, "num_cameras"),
    ("zajdel_adf", {"within_std": 1e308}, "within_std"),
    ("zajdel_adf", {"between_std": 0}, "between_std"),
    ("zajdel_adf", {"travel_mean": []}, "travel_mean"),
    ("zajdel_adf", {"travel_std": [[1.0, 2.0]]}, "travel_std"),
    ("zajdel_adf", {"stream_window": 5}, "stream_window"),  # learn-search's key
    ("zajdel_learnsearch", {"within_std": 1.0}, "within_std"),  # the ADF's key
    ("zajdel_learnsearch", {"travel_shrinkage": 1e308}, "travel_shrinkage"),
    ("zajdel_learnsearch", {"travel_mean": 1e308}, "travel_mean"),
    ("zajdel_learnsearch", {"em_tol": -1}, "em_tol"),
    ("zajdel_learnsearch", {"close_z": 3.0}, "close_z"),  # without stream_window
    ("zajdel_adf", {"within_std": 1e-300}, "within_std"),  # said "prior.kappa = 0.0"
    ("zajdel_learnsearch", {"travel_std": 1e-300}, "travel_std"),  # overflowed, ran to rc 0
    ("zajdel_learnsearch", {"window": 1e-300}, "window"),
    ("localization", {"duration": 1e308}, "duration"),
    ("localization", {"sigma_range": 0}, "sigma_range"),  # the likelihood divides by it
    ("localization", {"sigma_bearing": -0.1}, "sigma_bearing"),
    ("localization", {"max_range": 0}, "max_range"),
    ("localization", {"outlier_prob": 0}, "outlier_prob"),  # log(0) in the outlier term
    ("localization", {"outlier_prob": 1.0}, "outlier_prob"),
    ("localization", {"motion": [0.1, 0.1, 0.1]}, "motion"),
    ("localization", {"motion": [0.1, -0.1, 0.1, 0.1]}, "motion"),
    ("localization", {"initial_std": [0.1, 0.1, 0.1, 0.1]}, "initial_std"),
    ("localization", {"range_bias": "5cm"}, "range_bias"),
    ("localization", {"initial_pose": [1e200, 0, 0]}, "initial_pose"),  # ran to rc 0
    ("localization", {"initial_pose": [0, 0, -1e8]}, "initial_pose"),
    ("localization", {"motion": [1e200, 0, 0, 0]}, "motion"),  # ran to rc 0
    ("localization", {"range_bias": 2e7}, "range_bias"),
    ("localization", {"dt": 1e-9}, "dt"),  # 7.95e9 steps: asked for 59 GiB
    ("pathrecovery", {"c0": 0}, "c0"),  # without f0 it was ignored
    ("pathrecovery", {"c0": 16, "f0": [0.1, 0.2]}, "f0"),
    ("rjmcmc3d", {"tau": 1e308}, "tau"),  # six such fields overflowed once squared
    ("rjmcmc3d", {"min_sd": 1e308}, "min_sd"),
]


@pytest.mark.parametrize("name, config, key", RANGE_CASES)
def test_out_of_range_options_name_the_config_file_and_key(capsys, tmp_path, name, config, key):
    rc, err = _run(capsys, tmp_path, name, config)
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "opts.json" in err and key in err, err


def test_option_readers():
    cfg = {"a": 2, "b": 2.5, "c": True, "d": "x", "e": [[1, 2], [3, 4]], "f": "2", "g": 2.0,
           "h": [1, "x"], "i": float("nan"), "j": 10**400}
    assert integer(cfg, "a") == 2 and integer(cfg, "zz", 7) == 7
    assert number(cfg, "a") == 2.0 and number(cfg, "b") == 2.5 and number(cfg, "zz", 1) == 1.0
    assert flag(cfg, "c", False) is True and text(cfg, "d", "y") == "x"
    np.testing.assert_array_equal(array(cfg, "e", ndim=2), [[1.0, 2.0], [3.0, 4.0]])
    for fn, key in ((integer, "f"), (integer, "g"), (integer, "c"), (number, "f"),
                    (number, "c"), (number, "i"), (number, "j"), (flag, "a"), (text, "a"), (array, "h"),
                    (integer, "missing")):  # fmt: skip
        with pytest.raises(ConfigError, match=key):
            fn(cfg, key) if fn not in (flag, text) else fn(cfg, key, None)
    with pytest.raises(ConfigError, match="axes"):
        array(cfg, "e", ndim=1)
    for v in (True, [1.0, False], [[1.0], [True]]):  # numpy alone reads true as 1.0
        with pytest.raises(ConfigError, match="true / false"):
            array({"t": v}, "t")
    with pytest.raises(ConfigError, match="unknown config key"):
        check_keys(cfg, {"a"})
    assert build(StrokeConfig, {"gap_min": 3}).gap_min == 3
    with pytest.raises(ConfigError, match="gap_min"):  # an int field given a float
        build(StrokeConfig, {"gap_min": 3.5})
    with pytest.raises(ConfigError, match="iou_threshold"):  # the class's own check
        build(StrokeConfig, {"iou_threshold": 2.0})


def test_override_lays_scalar_fields_over_an_instance():
    """``override`` keeps the instance's other fields (not the class defaults), types
    each value as the field it sets, and names ``key.field`` in every refusal."""
    base = StrokeConfig(gap_min=3, gap_max=9)
    got = override(base, {"gap_max": 12, "iou_threshold": 0}, "strokes")
    assert got.gap_min == 3 and got.gap_max == 12  # gap_min is the instance's, not the default
    assert isinstance(got.iou_threshold, float) and got.iou_threshold == 0.0
    assert override(base, {}, "strokes") == base
    for fields, needle in (({"gap_max": 12.5}, "strokes.gap_max = 12.5"),
                           ({"gap_max": True}, "strokes.gap_max = True"),
                           ({"iou_threshold": "0.3"}, "strokes.iou_threshold = '0.3'"),
                           ({"iou_threshold": 2.0}, "config strokes: .*iou_threshold"),
                           ({"gap_mn": 1}, r"unknown or non-scalar StrokeConfig field\(s\) "
                                           r"\['gap_mn'\]"),
                           ([1], r"config strokes = \[1\]: expected an object")):
        with pytest.raises(ConfigError, match=needle):
            override(base, fields, "strokes")
    from models.jorge.network import NetworkConfig

    net = NetworkConfig()
    assert net.palette_missing_table  # a fitted table: switched off with [], or set
    off = override(net, {"palette_missing_table": []}, "network")
    assert off.palette_missing_table == () and off.palette_gain_table == net.palette_gain_table
    as_json = json.loads(json.dumps({"palette_missing_table": net.palette_missing_table}))
    assert override(off, as_json, "network") == net  # nested tuples of floats again, exactly
    bins = override(net, {"palette_gain_bins": [0, 2, 6, 8, 10]}, "network").palette_gain_bins
    assert bins == (0, 2, 6, 8, 10) and all(type(b) is int for b in bins)
    for field, value, needle in (
            ("palette_missing_table", False, "missing_table = False: expected a table"),
            ("palette_missing_table", [[[True]]], r"missing_table = \[\[\[True\]\]\]: expected a"),
            ("palette_missing_table", [[0.0]], "palette_missing_table must be a table of log"),
            ("palette_missing_table", [[[0.0]], [0.0]], "palette_missing_table must be a table"),
            ("palette_missing_table", [[["x"]]], "missing_table: expected finite numbers in"),
            ("palette_gain_bins", [0, 2.5], "palette_gain_bins: expected integers in"),
            ("palette_gain_bins", [], "palette_gain_bins must rise from 0")):
        with pytest.raises(ConfigError, match=f"config network.*{needle}"):
            override(net, {field: value}, "network")
    with pytest.raises(ConfigError, match="config labels: .*new_group_probs must sum to 1"):
        override(net.labels, {"new_group_probs": [0.5, 0.6]}, "labels")


def test_rjmcmc3d_floor_errors_name_their_source(capsys, tmp_path):
    """One view spans no floor: the error names its calibration file (whose camera centre
    the default floor comes from); a config floor that is not a rectangle names the
    config file."""
    view = str(DATA / "rjmcmc3d" / "view0")
    assert main(["track", "rjmcmc3d", view, "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "calibration.xml" in err and "give floor" in err, err
    rc, err = _run(capsys, tmp_path, "rjmcmc3d", {"floor": [1, 0, 0, 1]})
    assert rc == 2 and "opts.json" in err and "floor" in err, err


@pytest.mark.parametrize("method, key", [("bk", "num_particles"), ("particle", "clusters"),
                                         ("exact", "clusters"), ("auto", "bogus_key")])
def test_dbn_key_of_another_method_names_the_config_file(capsys, tmp_path, method, key):
    """Every method of ``dbntrack track dbn``, not only the default one, names the config
    file for a key it does not take (``inference.filter`` named the key alone)."""
    rc, err = _run(capsys, tmp_path, "dbn", {"method": method, key: 1})
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert "opts.json" in err and key in err and repr(method) in err, err
