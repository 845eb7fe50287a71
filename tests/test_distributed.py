"""Distributed tables and sweeps (waveoptics.distributed, CLI table/sweep).

The contract: a table computed in-process, on a 2-process LocalCluster (loopback), after a worker was killed
mid-run, or finished with --resume after an interruption is *bit-identical* (np.array_equal) to the in-process
table — tasks are deterministic and each block is stored exactly once. Grids are small (32², 4 wavelengths) to
keep the file well under a minute.
"""
import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import cloudpickle
import h5py
import numpy as np
import pytest

from waveoptics import colour
from waveoptics.request import SimulationRequest
from waveoptics import distributed as D
from waveoptics.brdf import twoscale
from waveoptics.cli import main
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.errors import OutputExistsError, WaveopticsError
from waveoptics.units import direction_from_angles

# task functions defined here run on worker processes, which cannot import this test module
cloudpickle.register_pickle_by_value(sys.modules[__name__])

NANO = "abc:sigma=8nm,B=2um,C=2.6"
CASE = SimulationRequest(material="Au", nano=NANO, micro_alpha=0.1, wavelengths_nm=(450.0, 520.0, 590.0, 660.0), resolution=32)
SPEC = D.TableSpec(CASE, thetas_deg=(0.0, 30.0, 60.0), batch=2)  # 3 angles x 2 batches = 6 tasks


def _arrays(path):
    t = D.read_table(path)
    return {k: getattr(t, k) for k in ("brdf", "microfacet", "albedo", "microfacet_albedo", "rgb", "albedo_rgb")}


def assert_same_table(a, b):
    A, B = _arrays(a), _arrays(b)
    for k in A:
        assert np.array_equal(A[k], B[k]), k


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The in-process table (the embedded default)."""
    out = tmp_path_factory.mktemp("ref") / "ref.h5"
    res = D.run_table(SPEC, out)
    assert res["computed"] == 6 and res["skipped"] == 0
    return out


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster with 2 single-threaded worker processes on loopback."""
    with D.local_cluster(2) as c:
        yield c


# ------------------------------------------------------------------------------------------------ task split

def test_tasks_cover_every_angle_and_wavelength_once():
    spec = D.TableSpec(SimulationRequest(wavelengths_nm=tuple(range(400, 710, 10)), resolution=16), thetas_deg=(0, 45),
                       batch=8)
    tasks = D.table_tasks(spec)
    assert spec.n_batches == 4 and len(tasks) == 2 * 4
    for t in (0, 1):
        covered = np.concatenate([np.arange(k.lo, k.hi) for k in tasks if k.t == t])
        assert np.array_equal(np.sort(covered), np.arange(31))
    sizes = {k.hi - k.lo for k in tasks}
    assert sizes <= {7, 8}  # balanced, never a tiny last batch
    assert len({k.name for k in tasks}) == len(tasks)


def test_table_spec_rejects_bad_values():
    with pytest.raises(WaveopticsError, match="above the horizon"):
        D.TableSpec(CASE, thetas_deg=(0, 90))
    with pytest.raises(WaveopticsError, match="appears twice"):
        D.TableSpec(CASE, thetas_deg=(10, 10))
    with pytest.raises(WaveopticsError, match="^batch 0 is not allowed") as exc:   # the field, not the CLI flag
        D.TableSpec(CASE, thetas_deg=(10,), batch=0)
    assert exc.value.field == "batch"
    with pytest.raises(WaveopticsError, match="PSD route is already the ensemble mean"):
        D.run_table(D.TableSpec(CASE, thetas_deg=(10,), realizations=2), "/nonexistent-dir-xyz/t.h5")


# ------------------------------------------------------------------------------------------------ in-process

def test_table_layout_and_values(reference):
    with h5py.File(reference, "r") as f:
        assert f.attrs["format"] == D.TABLE_FORMAT
        assert f["brdf"].shape == (3, 4, 32, 32) and f["brdf"].dtype == np.float32
        assert [d.label for d in f["brdf"].dims] == ["theta_i", "wavelength", "v", "u"]
        assert np.array_equal(f["brdf"].dims[1][0][()], CASE.wavelengths_nm)
        assert np.array_equal(f["theta_i"][()], [0.0, 30.0, 60.0])
        assert f["wavelength"].attrs["units"] == "nm"
        params = json.loads(f.attrs["parameters"])
        assert params["material"] == "Au" and params["nano"] == NANO and params["incident_theta_deg"] == [0, 30, 60]
        assert f["task_cost_s"].shape == (1, 3, 2) and np.all(f["task_cost_s"][()] > 0)
        assert "brdf_realizations" not in f
    t = D.read_table(reference)
    assert np.all(np.isfinite(t.brdf)) and np.all(t.brdf >= 0)
    # each block equals a direct evaluation of the whole spectrum at that angle (batching changes nothing)
    L = twoscale.evaluate(direction_from_angles(30.0, 0.0), CASE.wavelengths(), "Au", CASE.micro(),
                          D.cases.case_nano(CASE, 0, CASE.wavelengths()), DirectionGrid.hemisphere(32))
    np.testing.assert_allclose(t.brdf[1], L.total.astype(np.float32), rtol=1e-6, atol=0)
    np.testing.assert_allclose(t.albedo[1], L.albedo(), rtol=1e-12)
    # RGB of the albedo spectrum is the colour pipeline's, per incident angle
    np.testing.assert_allclose(t.albedo_rgb, colour.reflectance_to_rgb(t.albedo, t.wavelengths_nm), rtol=1e-12)
    # physics: nano-roughness redistributes the light the facets reflect; it adds none. Not ≤ the microfacet albedo
    # exactly: a facet whose mirror direction is masked still sends part of its diffracted lobe out, unmasked
    # (Walter's facet integral, docs/physics.md §7; measured +2.5e-4 at 60° on these 32² cells), as the two-scale
    # tests allow (1e-3, tests/test_twoscale.py)
    assert np.all(t.albedo <= t.microfacet_albedo * (1 + 1e-3))
    assert t.grid.n_u == 32 and t.grid.u_range == (-1.0, 1.0)


def test_existing_outputs_are_refused_and_complete_resume_is_a_no_op(reference, tmp_path):
    with pytest.raises(OutputExistsError, match="overwrite=True"):
        D.run_table(SPEC, reference)
    res = D.run_table(SPEC, reference, resume=True)
    assert res["computed"] == 0 and res["skipped"] == 6
    other = D.TableSpec(SimulationRequest(**{**CASE.__dict__, "material": "Ag"}), thetas_deg=SPEC.thetas_deg, batch=2)
    with pytest.raises(WaveopticsError, match="different parameters"):
        D.run_table(other, reference, resume=True)


# ------------------------------------------------------------------------------------------------ cluster

@pytest.mark.parametrize("workers", [None, 1])
def test_clusters_listen_on_loopback_only(workers):
    """The machine's network rules: no socket of ours may listen beyond 127.0.0.1 (dashboard_address=None alone
    leaves the scheduler's and workers' HTTP servers on 0.0.0.0)."""
    import psutil

    with D.dask_client(workers=workers) as client:
        assert client.submit(sum, [1, 2], pure=False).result() == 3
        me = psutil.Process()
        procs = [me, *me.children(recursive=True)]
        listening = [c.laddr for p in procs for c in p.net_connections(kind="inet") if c.status == psutil.CONN_LISTEN]
    assert listening and all(a.ip == "127.0.0.1" for a in listening), listening


def test_workers_get_no_memory_trim_setting_from_dask(cluster):
    """Dask's default MALLOC_TRIM_THRESHOLD_=65536 doubles a task's CPU time (docs/scaling.md): workers must see
    the client's environment, not Dask's value."""
    from distributed import Client

    with Client(cluster) as client:
        seen = set(client.run(os.environ.get, "MALLOC_TRIM_THRESHOLD_").values())
    assert seen == {os.environ.get("MALLOC_TRIM_THRESHOLD_")}


def test_local_cluster_gives_the_same_table(reference, cluster, tmp_path):
    out = tmp_path / "cluster.h5"
    res = D.run_table(SPEC, out, scheduler=cluster.scheduler_address)
    assert res["computed"] == 6
    assert_same_table(out, reference)


def _kill_worker_once(spec, task, surface=None, device=None, *, marker):
    """Task function that kills its own worker process the first time it runs task (θ index 1, batch 0)."""
    m = Path(marker)
    if task.t == 1 and task.b == 0 and not m.exists():
        m.write_text(str(os.getpid()))
        os._exit(1)
    return D.compute_block(spec, task, surface, device)


def test_killed_worker_loses_and_duplicates_nothing(reference, cluster, tmp_path):
    import functools

    from distributed import Client

    marker = tmp_path / "killed"
    out = tmp_path / "killed.h5"
    with Client(cluster) as client:
        res = D.run_table(SPEC, out, client=client, task_fn=functools.partial(_kill_worker_once, marker=str(marker)))
        client.wait_for_workers(2, timeout=60)  # the nanny restarted the killed worker
    assert marker.exists()  # a worker really died mid-run
    assert sorted(res["written"]) == sorted(t.name for t in D.table_tasks(SPEC))  # each task stored exactly once
    assert_same_table(out, reference)


def test_workers_option_starts_a_local_cluster(reference, tmp_path):
    """The --workers N path (its own LocalCluster); sweeps share the machinery."""
    out = tmp_path / "w2.h5"
    D.run_table(SPEC, out, workers=2)
    assert_same_table(out, reference)


def _runtimes_in_this_process():
    from waveoptics import runtime

    return len(runtime._runtimes)


def test_direct_solver_builds_one_opencl_context_per_worker(rt, cluster, tmp_path):
    """The OpenCL route on worker processes: each worker creates its context once (the WarmWorker plugin, then
    runtime.get_runtime's per-process cache), and the table matches the in-process one."""
    from distributed import Client

    from waveoptics import surfaces

    hf = surfaces.generate("gaussian", sigma="15nm", corr_length="1um", size="8um", samples=64, seed=2)
    case = SimulationRequest(material="Al", nano=None, surface="generated", micro_alpha=0.0, wavelengths_nm=(500.0, 600.0),
                  resolution=16, solver="direct")
    spec = D.TableSpec(case, thetas_deg=(0.0, 30.0, 50.0), batch=2)
    D.run_table(spec, tmp_path / "ref.h5", surface=hf)
    with Client(cluster) as client:
        D.run_table(spec, tmp_path / "direct.h5", surface=hf, client=client)
        counts = client.run(_runtimes_in_this_process)
    assert set(counts.values()) == {1}, counts
    a, b = D.read_table(tmp_path / "ref.h5"), D.read_table(tmp_path / "direct.h5")
    assert np.all(np.isfinite(a.brdf)) and a.albedo.max() > 0
    assert np.array_equal(a.brdf, b.brdf)


# ------------------------------------------------------------------------------------------------ resume

def _fail_on(spec, task, surface=None, device=None, *, bad):
    if task.name == bad:
        raise RuntimeError(f"injected failure in {task.name}")
    return D.compute_block(spec, task, surface, device)


def test_resume_after_a_failed_run_completes_the_table(reference, tmp_path):
    import functools

    out = tmp_path / "resume.h5"
    bad = D.table_tasks(SPEC)[3].name
    with pytest.raises(RuntimeError, match="injected failure"):
        D.run_table(SPEC, out, retries=1, task_fn=functools.partial(_fail_on, bad=bad))
    part = D.partial_path(out)
    assert not out.exists() and part.is_dir()
    assert not (part / "items" / f"{bad}.npz").exists()
    # a half-written block (temporary name of io.atomic_path) never counts as done
    (part / "items" / f".{bad}.npz.xyz.partial.npz").write_bytes(b"half")
    with pytest.raises(OutputExistsError, match="pass resume=True"):
        D.run_table(SPEC, out)
    other = D.TableSpec(CASE, thetas_deg=(0.0, 30.0, 60.0), batch=4)
    with pytest.raises(WaveopticsError, match="different parameters.*batch"):
        D.run_table(other, out, resume=True)
    res = D.run_table(SPEC, out, resume=True)
    assert res["computed"] >= 1 and res["computed"] + res["skipped"] == 6 and bad in res["written"]
    assert not part.exists()
    assert_same_table(out, reference)


def test_resume_after_the_client_process_is_killed(reference, tmp_path):
    """A hard crash (os._exit of the whole in-process run after 2 stored blocks) keeps the finished blocks."""
    out = tmp_path / "crash.h5"
    code = textwrap.dedent(f"""
        import os, functools
        from pathlib import Path
        from waveoptics import distributed as D
        from waveoptics.distributed import TableSpec
        from waveoptics.request import SimulationRequest

        SPEC = {SPEC!r}
        items = D.partial_path({str(out)!r}) / "items"

        def crash_after_two(spec, task, surface=None, device=None):
            if items.is_dir() and len(list(items.glob("r*.npz"))) >= 2:
                os._exit(3)
            return D.compute_block(spec, task, surface, device)

        D.run_table(SPEC, {str(out)!r}, task_fn=crash_after_two)
    """)
    root = Path(__file__).resolve().parent.parent
    proc = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONPATH": str(root)})
    assert proc.returncode == 3, proc.stderr[-2000:]
    assert not out.exists()
    done = sorted(p.name for p in (D.partial_path(out) / "items").glob("r*.npz"))
    assert 2 <= len(done) < 6
    res = D.run_table(SPEC, out, resume=True)
    assert res["skipped"] == len(done) and res["computed"] == 6 - len(done)
    assert_same_table(out, reference)


# ------------------------------------------------------------------------------------------------ realizations

def test_realizations_of_a_height_field_average_into_brdf(tmp_path):
    from waveoptics import surfaces

    hf = surfaces.generate("gaussian", sigma="20nm", corr_length="1um", size="32um", samples=256, seed=1)
    case = SimulationRequest(material="Al", nano=None, surface="generated", micro_alpha=0.0, wavelengths_nm=(500.0, 600.0),
                  resolution=16, solver="fft")
    spec = D.TableSpec(case, thetas_deg=(20.0,), realizations=2, batch=2)
    out = tmp_path / "real.h5"
    D.run_table(spec, out, surface=hf)
    t = D.read_table(out)
    assert t.brdf_realizations.shape == (2, 1, 2, 16, 16)
    np.testing.assert_allclose(t.brdf, t.brdf_realizations.astype(np.float64).mean(axis=0), rtol=1e-6)
    assert not np.array_equal(t.brdf_realizations[0], t.brdf_realizations[1])  # two different tiles
    assert t.params["surface_digest"] == D.surface_digest(hf)


# ------------------------------------------------------------------------------------------------ sweeps

def test_parse_vary_lists():
    name, vals = D.parse_vary("sigma_nano=1nm:20nm:5")
    assert name == "sigma_nano"
    np.testing.assert_allclose(vals, [1e-9, 6e-9, 11e-9, 16e-9], rtol=1e-12)
    assert D.parse_vary("sigma_nano=1nm:2nm:500pm")[1] == pytest.approx([1e-9, 1.5e-9, 2e-9])
    assert D.parse_vary("material=Au,Ag,Cu") == ("material", ["Au", "Ag", "Cu"])
    assert D.parse_vary("material=f0:0.9,0.6,0.3;Au")[1] == ["f0:0.9,0.6,0.3", "Au"]
    assert D.parse_vary("nano.B=1um,5um", CASE)[1] == pytest.approx([1e-6, 5e-6])
    assert D.parse_vary("micro_alpha=0.1:0.3:0.1")[1] == pytest.approx([0.1, 0.2, 0.3])
    assert D.value_text("sigma_nano", 6e-9) == "6nm" and D.value_text("nano.B", 2e-6) == "2um"
    with pytest.raises(WaveopticsError, match="vary: unknown parameter 'sigma_nanoo'.*did you mean 'sigma_nano'"):
        D.parse_vary("sigma_nanoo=1nm")
    with pytest.raises(WaveopticsError, match="NAME=VALUES"):
        D.parse_vary("material")
    with pytest.raises(WaveopticsError, match="START needs a unit"):
        D.parse_vary("sigma_nano=1:20:5")


def test_sweep_points_are_the_cartesian_product():
    pts = D.sweep_points(CASE, [("material", ["Au", "Ag"]), ("sigma_nano", [1e-9, 5e-9, 9e-9])])
    assert len(pts) == 6
    assert [p[0]["material"] for p in pts] == ["Au"] * 3 + ["Ag"] * 3
    assert pts[4][1].material == "Ag" and pts[4][1].nano.startswith("abc:sigma=5.0000000000000001e-09m")
    with pytest.raises(WaveopticsError, match="given twice"):
        D.sweep_points(CASE, [("kd", [0.1]), ("kd", [0.2])])
    # α_y of an anisotropic micro NDF: each point carries it into its micro NDF; an isotropic-only NDF refuses it
    pts = D.sweep_points(CASE, [("alpha_y", D.parse_vary("alpha_y=0.1,0.3")[1])])
    assert [p[1].micro().alpha_y for p in pts] == [0.1, 0.3] and pts[1][0]["alpha_y"] == 0.3
    with pytest.raises(WaveopticsError, match="alpha_y"):
        D.sweep_points(dataclasses.replace(CASE, ndf="blinn-phong"), [("alpha_y", [0.2])])


SWEEP_BASE = SimulationRequest(material="Au", nano=NANO, micro_alpha=0.1, wavelengths_nm=(450.0, 600.0), resolution=16)
SWEEP_VARY = [("material", ["Au", "Ag"]), ("sigma_nano", [0.5e-9, 4e-9, 12e-9])]


def test_sweep_summaries_and_resume(tmp_path):
    import functools

    out = tmp_path / "sweep.csv"
    with pytest.raises(RuntimeError, match="injected"):
        D.run_sweep(SWEEP_BASE, SWEEP_VARY, out, sphere_size=16, retries=0,
                    task_fn=functools.partial(_sweep_fail, bad="Ag"))
    res = D.run_sweep(SWEEP_BASE, SWEEP_VARY, out, sphere_size=16, resume=True)
    assert res["skipped"] >= 1 and res["computed"] + res["skipped"] == 6
    rows = D.read_sweep(out)
    assert [r["material"] for r in rows] == ["Au"] * 3 + ["Ag"] * 3
    assert [r["sigma_nano"] for r in rows[:3]] == ["0.5nm", "4nm", "12nm"]
    for mat in ("Au", "Ag"):
        dE = [float(r["dE_albedo"]) for r in rows if r["material"] == mat]
        # σ_nano → 0 is the microfacet model; more nano-roughness moves further from it
        assert dE[0] < 0.05 and dE[0] < dE[1] < dE[2]
        cf = [float(r["coherent_fraction"]) for r in rows if r["material"] == mat]
        assert cf[0] > cf[1] > cf[2]
    assert all(float(r["cost_s"]) > 0 for r in rows)
    assert set(D.SWEEP_COLUMNS) <= set(rows[0])


def _sweep_fail(case, *, bad, **kw):
    if case.material == bad:
        raise RuntimeError("injected failure")
    return D.sweep_point(case, **kw)


# ------------------------------------------------------------------------------------------------ CLI

def test_cli_table_and_sweep(tmp_path, capsys):
    out = tmp_path / "cli.h5"
    rc = main(["table", "--nano", NANO, "--material", "Au", "--micro-alpha", "0.1", "--incident-angles", "0:60:30",
               "--wavelengths", "450,520,590,660", "--resolution", "32", "--batch", "2", "-o", str(out), "--json"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    assert data["tasks"] == 6 and data["complete"] and data["wavelengths"] == 4
    t = D.read_table(out)
    assert t.brdf.shape == (3, 4, 32, 32)
    assert main(["table", "--nano", NANO, "-o", str(out)]) == 2
    assert "already exists" in capsys.readouterr().err
    s = tmp_path / "s.json"
    rc = main(["sweep", "--nano", NANO, "--vary", "material=Au,Cu", "--wavelengths", "500,600", "--resolution", "16",
               "--no-spheres", "-o", str(s)])
    rows = json.loads(s.read_text())
    assert rc == 0 and len(rows) == 2              # --no-spheres: simulate's option, --sphere-size 0 here
    assert all(r["dE_sphere_mean"] is None and r["dE_sphere_max"] is None for r in rows)   # not computed, not 0


@pytest.mark.parametrize("argv, message", [
    (["table", "--incident-angles", "0:90:30"], "above the horizon"),
    (["table", "--scheduler", "localhost:8786"], "tcp://HOST:PORT"),
    (["table", "--workers", "0"], "--workers 0"),
    (["table", "--batch", "0"], "--batch 0"),
    (["table", "--nano", "abc:sigma=5nm", "--material", "Au"], "lacks B, C"),
    (["table", "--material", "Unobtainium"], "Unobtainium"),
    (["sweep", "--vary", "colour=red"], "--vary: unknown parameter 'colour'"),
    (["sweep", "--vary", "material=Au", "--light", "sun"], "--light names a light of a scene file"),
])
def test_cli_errors_are_one_line(argv, message, tmp_path, capsys):
    out = tmp_path / ("o.csv" if argv[0] == "sweep" else "o.h5")
    assert main([*argv, "--wavelengths", "550", "--resolution", "16", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err
    assert not out.exists() and not D.partial_path(out).exists()


def test_sweep_help_lists_every_vary_name():
    from waveoptics.cli import sweep

    assert tuple(sweep.VARY_NAMES) == tuple(D.VARY)


def test_scene_file_gives_the_case(tmp_path):
    scene = tmp_path / "gold.toml"
    scene.write_text(textwrap.dedent("""
        seed = 4
        [accuracy]
        delta_e = 2.0
        [[materials]]
        name = "gold"
        material = "Au"
        roughness = 0.12
        ndf = "ggx"
        [materials.nano]
        statistics = "abc:sigma=5nm,B=2um,C=2.6"
        [[lights]]
        name = "lamp"
        spd = "A"
        directions_deg = [[25, 10]]
        [output]
        resolution = 24
    """))
    from waveoptics.planning import scene as scene_mod

    case, hf = D.case_from_scene(scene_mod.load(scene))
    assert hf is None
    assert (case.material, case.micro_alpha, case.ndf, case.illuminant, case.resolution, case.seed) == \
        ("Au", 0.12, "ggx", "A", 24, 4)
    assert case.nano == "abc:sigma=5nm,B=2um,C=2.6" and case.incident_deg == (25.0, 10.0)
    assert case.delta_e == 2.0
    out = tmp_path / "scene.h5"
    assert main(["table", str(scene), "--incident-angles", "0,40", "--wavelengths", "500,600", "-o", str(out)]) == 0
    t = D.read_table(out)
    assert t.brdf.shape == (2, 2, 24, 24) and t.params["illuminant"] == "A" and t.params["ndf"] == "ggx"
    with pytest.raises(WaveopticsError, match="no material 'silver'"):
        D.case_from_scene(scene_mod.load(scene), material="silver")
