"""Sweeps on Dask distributed (models.experiments): identical to serial, resumable,
robust to a failing task and to a worker that dies."""

from __future__ import annotations

import json
import re

import pytest

from benchmarks.scale_out import chain_task
from dbn.errors import InputError
from models.experiments import GridPoint, make_grid, read_results, run_grid


def _strip(records):
    return [(r["id"], r["status"], r["result"]) for r in records]


def test_grid_is_the_cartesian_product_with_stable_ids() -> None:
    grid = make_grid(["a", "b"], ["d1"], seeds=[0, 1], params={"n": [1, 2], "k": ["x"]})
    assert len(grid) == 8
    assert grid[0] == GridPoint("a", "d1", 0, (("k", "x"), ("n", 1)))
    again = make_grid(["a", "b"], ["d1"], seeds=[0, 1], params={"k": ["x"], "n": [1, 2]})
    assert [p.id for p in grid] == [p.id for p in again]
    assert len({p.rng_seed for p in grid}) == 8
    assert GridPoint.from_dict(grid[3].as_dict()) == grid[3]


@pytest.mark.parametrize("params", [{"n": []}, {"n": "abc"}, {"n": 3}])
def test_bad_grid_parameter_is_rejected(params) -> None:
    with pytest.raises(InputError, match="'n'"):
        make_grid(["a"], params=params)


@pytest.mark.parametrize(("kwargs", "needle"), [
    ({"trackers": "chains"}, "trackers must be a non-empty list of names, got 'chains'"),
    ({"trackers": [5]}, "trackers must be a non-empty list of names"),
    ({"data": [5]}, "data must be a non-empty list of names"),
    ({"seeds": "abc"}, "seeds must be a non-empty list of integers >= 0"),
    ({"seeds": []}, "seeds must be a non-empty list of integers >= 0"),
    ({"seeds": [1.5]}, "each seed must be an integer >= 0, got 1.5"),
    ({"seeds": [True]}, "each seed must be an integer >= 0, got True"),
    ({"seeds": [-1]}, "each seed must be an integer >= 0, got -1"),
])  # fmt: skip
def test_bad_grid_names_and_seeds_are_rejected(kwargs, needle) -> None:
    """A tracker name given as a string was split into its letters, a text seed raised
    Python's ValueError, 1.5 was truncated, True read as 1, and -1 failed only inside a
    worker (make_rng)."""
    with pytest.raises(InputError) as exc:
        make_grid(**{"trackers": ["chains"], **kwargs})
    assert needle in str(exc.value)


def test_run_grid_refuses_a_task_grid_or_address_it_cannot_use(tmp_path) -> None:
    """A task of None ran every point to an 'error' record; a list of names raised
    AttributeError, one GridPoint TypeError, and an address without a port dask's
    ValueError. Nothing is written."""
    grid = make_grid(["chains"], params={"n": [3], "T": [5]})
    out = tmp_path / "r.jsonl"
    for kwargs, needle in (({"task": None}, "task must be a function"),
                           ({"grid": ["a"]}, "grid[0] must be an instance of GridPoint"),
                           ({"grid": grid[0]}, "grid must be a list of GridPoint")):  # fmt: skip
        with pytest.raises(InputError) as exc:
            run_grid(**{"task": chain_task, "grid": grid, **kwargs}, out=out, serial=True)
        assert needle in str(exc.value)
    assert not out.exists()
    with pytest.raises(InputError, match="client 'abc': cannot connect to a Dask scheduler"):
        run_grid(chain_task, grid, client="abc", progress=False)


def test_duplicate_points_and_resume_without_file_are_rejected(tmp_path) -> None:
    p = GridPoint("chains")
    with pytest.raises(InputError, match="duplicate"):
        run_grid(chain_task, [p, p], serial=True)
    with pytest.raises(InputError, match="out="):
        run_grid(chain_task, [p], serial=True, resume=True)


def test_parameters_a_task_does_not_read_are_refused_before_anything_runs(tmp_path) -> None:
    """A misspelt name (``N`` for chain_task's ``n``) ran every point with the default,
    and example_task ignored any parameter; a task that declares none is not checked."""
    from models.experiments import check_params, example_task, load_sweep

    typo = make_grid(["chains"], params={"N": [4], "T": [5]})
    out = tmp_path / "r.jsonl"
    with pytest.raises(InputError, match=r"\['N'\] are not read by chain_task \(it reads: T, "):
        run_grid(chain_task, typo, serial=True, out=out)
    assert not out.exists()  # refused before the results file is opened
    with pytest.raises(InputError, match="example_task .it reads: none"):
        check_params(example_task, make_grid(["jorge"], params={"num_particles": [10]}))
    check_params(lambda p: {}, typo)  # undeclared: taken at its word
    check_params(chain_task, make_grid(["chains"], params={"n": [4], "T": [5]}))
    toml = tmp_path / "sweep.toml"
    toml.write_text('task = "benchmarks.scale_out:chain_task"\ntrackers = ["chains"]\n'
                    '[params]\nn = [4]\ntee = [5]\n')  # fmt: skip
    with pytest.raises(InputError, match=r"sweep.toml.*\['tee'\]"):
        load_sweep(toml)


_HEAD = 'task = "benchmarks.scale_out:chain_task"\ntrackers = ["chains"]\n'


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        # a misspelt field ran the defaults: one seed 0, no grid parameter
        ("seed = [3]\n", "unknown field(s) ['seed']"),
        ("seeds = [0]\n[param]\nn = [4]\n", "unknown field(s) ['param']"),
        # an empty range or list ran nothing and said "0 of 0 points ok"
        ("seeds = {start = 3, stop = 1}\n", "field 'seeds' gives no seed"),
        ("seeds = []\n", "field 'seeds' gives no seed"),
        # an unknown key of the range started it at 0
        ("seeds = {begin = 2, stop = 4}\n", "field 'seeds': keys ['begin']"),
        # was Python's "cannot convert dictionary update sequence element #0"
        ("params = [1]\n", "field 'params' must be a table"),
    ],
)
def test_a_misspelt_or_empty_sweep_field_is_refused(tmp_path, body, needle) -> None:
    from models.experiments import load_sweep

    toml = tmp_path / "sweep.toml"
    toml.write_text(_HEAD + body)
    with pytest.raises(InputError, match=re.escape(needle)):
        load_sweep(toml)
    good = _HEAD + "seeds = {start = 1, stop = 3}\n[params]\nn = [4]\n"
    for text in (good, "\ufeff" + good):  # a byte-order mark first was "not a TOML file"
        toml.write_text(text, encoding="utf-8")
        grid = load_sweep(toml)[1]
        assert [(g.seed, g.params) for g in grid] == [(1, (("n", 4),)), (2, (("n", 4),))]


def test_serial_failing_task_is_recorded_and_others_finish(tmp_path) -> None:
    grid = [GridPoint("chains", seed=0, params=(("n", 3), ("T", 20)))]
    grid.append(GridPoint("chains", seed=1, params=(("fail", True), ("n", 3))))
    out = tmp_path / "r.jsonl"
    recs = run_grid(chain_task, grid, serial=True, out=out)
    assert [r["status"] for r in recs] == ["ok", "error"]
    assert "fails on purpose" in recs[1]["error"] and recs[1]["result"] is None
    assert _strip(read_results(out)) == _strip(recs)


def test_resume_runs_only_what_is_missing(tmp_path) -> None:
    grid = make_grid(["chains"], seeds=range(4), params={"n": [3], "T": [20]})
    out = tmp_path / "r.jsonl"
    first = run_grid(chain_task, grid[:2], serial=True, out=out)
    full = run_grid(chain_task, grid, serial=True, out=out, resume=True)
    lines = read_results(out)
    assert len(lines) == 4  # the two done points were not run again
    assert full[:2] == first  # returned as recorded (same wall_s: not re-run)
    assert _strip(full) == _strip(run_grid(chain_task, grid, serial=True))


def test_truncated_last_line_is_skipped_but_a_corrupt_record_is_an_error(tmp_path) -> None:
    out = tmp_path / "r.jsonl"
    rec = json.dumps({"id": "x", "status": "ok"})
    out.write_text(rec + "\n" + rec[:10])
    assert len(read_results(out)) == 1
    out.write_text(rec[:10] + "\n" + rec + "\n")
    with pytest.raises(InputError, match="line 1"):
        read_results(out)


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("dask.distributed")
    from models.experiments import local_cluster

    with local_cluster(2) as cluster, distributed.Client(cluster) as c:
        yield c


def test_two_workers_equal_the_serial_run_bit_for_bit(client, tmp_path) -> None:
    grid = make_grid(["chains"], seeds=range(6), params={"n": [5], "T": [50]})
    serial = run_grid(chain_task, grid, serial=True)
    dist = run_grid(chain_task, grid, client=client, out=tmp_path / "d.jsonl")
    assert _strip(dist) == _strip(serial)
    assert _strip(read_results(tmp_path / "d.jsonl")) != []


def test_a_worker_that_dies_mid_task_loses_nothing(client, tmp_path) -> None:
    marker = tmp_path / "died"
    grid = make_grid(["chains"], seeds=range(4), params={"n": [4], "T": [30]})
    grid[2] = GridPoint("chains", seed=2, params=(("T", 30), ("die_once", str(marker)), ("n", 4)))
    recs = run_grid(chain_task, grid, client=client)
    assert marker.exists()  # a worker process really died
    assert [r["status"] for r in recs] == ["ok"] * 4
    assert recs[2]["result"] == chain_task(GridPoint("chains", seed=2, params=grid[2].params))


def test_a_failing_task_on_the_cluster_is_recorded(client) -> None:
    grid = [GridPoint("chains", seed=0, params=(("n", 3),))]
    grid.append(GridPoint("chains", seed=1, params=(("fail", True),)))
    assert [r["status"] for r in run_grid(chain_task, grid, client=client)] == ["ok", "error"]


@pytest.mark.heavy  # ~11 s: a learn-search stream point twice; CI runs it (pytest -m heavy)
def test_benchmark_dask_flag_needs_a_mapper_and_runs_the_seed_loop_on_it(client) -> None:
    from benchmarks.__main__ import main
    from benchmarks.zajdel_learnsearch import _stream_point

    with pytest.raises(SystemExit) as exc:
        main(["scale_out", "--dask"])  # scale_out has no multi-seed loop to distribute
    assert exc.value.code == 2

    def mapper(fn, items):
        return client.gather(client.map(fn, list(items), pure=False))

    # the seed loop's function runs on workers and returns what it returns serially
    remote = mapper(_stream_point, [0])[0]
    local = _stream_point(0)
    assert {k: v for k, v in remote.items() if k != "seconds"} == {
        k: v for k, v in local.items() if k != "seconds"
    }


@pytest.mark.heavy  # ~9-16 s: dbntrack track 4 times on workers; CI runs it (pytest -m heavy)
def test_track_runs_on_two_workers_equal_the_serial_run(client, tmp_path) -> None:
    """``models.track.sweep_task.track_task`` (``dbntrack track`` on files) on a cluster:
    the same results as in this process, timings aside."""
    from pathlib import Path

    from models.track.sweep_task import track_task

    xml = Path(__file__).resolve().parent.parent / "data" / "jorge" / "caviar.xml"
    grid = make_grid(["jorge"], [f"'{xml}' --truth '{xml}'"], seeds=[0, 1],
                     params={"network.max_gap_frames": [10, 30]})  # fmt: skip

    def results(records):
        assert [r["status"] for r in records] == ["ok"] * 4, records
        return [(r["id"], {k: v for k, v in r["result"].items() if k != "timings_s"})
                for r in records]  # fmt: skip

    serial = results(run_grid(track_task, grid, serial=True, progress=False))
    assert results(run_grid(track_task, grid, client=client, progress=False)) == serial
    assert len({json.dumps(r["metrics"], sort_keys=True) for _, r in serial}) > 1
