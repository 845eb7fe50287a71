"""The accuracy–cost study machinery (waveoptics.study.accuracy_cost): Pareto dominance, the recommendation, the error measures
(pooling onto coarser grids, spectral interpolation), the reference (the exact fft solver agrees with the direct
float64 sum, docs/physics.md §1), the budget, the JSON layout and the CLI. Nothing here checks a timing.
"""
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli_helpers import run_cli
from waveoptics.study import accuracy_cost as cost
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.errors import WaveopticsError

LASER = "laser:465,532,638"       # three wavelengths whatever the colour accuracy: small and fast
MODEL = "gaussian:sigma=25nm,corr_length=0.6um"

#: tolerances, in one place
TOL = {
    "fft_vs_direct64": 1e-6,       # fft order auto (exact to 1e-8 Σw in U) vs the direct float64 reference
    "direct32": 1e-4,              # direct float32 vs float64 (relative L2 of the lobe)
}

ROW_KEYS = {"solver", "resolution", "wavelengths", "precision", "error_rel_l2", "error_albedo", "delta_e2000",
            "time_s", "realizations", "delta_e", "wavelengths_nm", "warnings", "skipped", "same_as_reference"}


@pytest.fixture(scope="module")
def small_study():
    cfg = cost.model_config(MODEL, "3.2um", 24, material="Al", illuminant=LASER, seed=3)
    st_ = cost.ladder(("fft0", "fft", "direct"), (8, 16), (1.0,), (1, 2), ("float32", "float64"))
    return cfg, st_, cost.study(cfg, st_, target_error=1e-3, reference_solver="direct")   # the independent reference


def test_pareto_front_by_hand():
    t = [1.0, 2.0, 3.0, 4.0, 2.0, 5.0, float("nan")]
    e = [5.0, 3.0, 4.0, 1.0, 3.0, 1.0, 0.0]
    # 2 is dominated by 1; 5 by 3 (same error, slower); 1 and 4 tie (neither strictly better): both stay;
    # NaN (a skipped setting) never belongs
    assert cost.pareto_front(t, e) == [0, 1, 4, 3]
    assert cost.pareto_front([], []) == []


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.001, 100), st.floats(1e-9, 10)), min_size=1, max_size=30))
def test_pareto_front_properties(points):
    t, e = (list(x) for x in zip(*points))
    front = cost.pareto_front(t, e)
    assert front, "a non-empty set has a non-empty front"
    for i in range(len(t)):
        dominated = any(t[j] <= t[i] and e[j] <= e[i] and (t[j] < t[i] or e[j] < e[i]) for j in range(len(t)))
        assert (i in front) == (not dominated)
    assert [t[i] for i in front] == sorted(t[i] for i in front)
    # along the front (by time) the error never increases
    errs = [e[i] for i in front]
    assert all(a >= b for a, b in zip(errs, errs[1:]))


def test_recommend_fastest_meeting_target():
    rows = [{"error_rel_l2": 0.1, "time_s": 1.0}, {"error_rel_l2": 0.01, "time_s": 3.0},
            {"error_rel_l2": 0.005, "time_s": 2.0}, {"error_rel_l2": None, "time_s": None}]
    assert cost.recommend(rows, 0.02) == 2
    assert cost.recommend(rows, 0.5) == 0
    assert cost.recommend(rows, 1e-4) is None
    with pytest.raises(WaveopticsError, match="metric"):
        cost.recommend(rows, 0.1, metric="error_linf")


def test_pooling_and_spectral_interpolation():
    rng = np.random.default_rng(0)
    E = rng.uniform(size=(2, 8, 8))
    P = cost._pool(E, 4)
    assert P.shape == (2, 2, 2) and np.isclose(P.sum(), E.sum())
    w = np.array([400.0, 500.0, 700.0])
    vals = 3.0 + 0.01 * w                                   # linear in λ: interpolation is exact
    out = cost._interp_wavelengths(vals, w, np.array([380.0, 450.0, 600.0, 700.0, 720.0]))
    assert np.allclose(out, [3.0 + 4.0, 3.0 + 4.5, 3.0 + 6.0, 3.0 + 7.0, 3.0 + 7.0])   # clamped at the ends


def test_errors_of_a_run_against_itself_are_zero():
    g = DirectionGrid.hemisphere(8)
    E = np.random.default_rng(1).uniform(size=(3, 8, 8))
    run = cost.Run(np.array([450.0, 550.0, 650.0]), g, E, E.sum(axis=(1, 2)), np.array([0.5, 0.4, 0.3]), 0.1)
    err = cost.errors(run, run)
    assert err == {"error_rel_l2": 0.0, "error_albedo": 0.0, "delta_e2000": 0.0}


def test_study_json_layout(small_study):
    cfg, st_, res = small_study
    assert {"config", "reference", "settings", "pareto", "metric", "target_error", "recommendation", "skipped",
            "budget_s", "time_s"} <= set(res)
    assert len(res["settings"]) == len(st_) == 2 * 2 * (1 + 1 + 2)
    for row in res["settings"]:
        assert ROW_KEYS <= set(row)
        assert row["time_s"] > 0 and row["wavelengths"] == 3
        for k in ("error_rel_l2", "error_albedo", "delta_e2000", "ensemble_rel_l2"):
            assert np.isfinite(row[k]) and row[k] >= 0
    ref = res["reference"]
    assert ref["solver"] == "direct" and ref["precision"] == "float64" and ref["resolution"] == 16
    assert ref["realizations"] == cost.REFERENCE_REALIZATIONS and 0 < ref["noise_rel_l2"] < 1
    assert all(0 <= i < len(st_) for i in res["pareto"])
    json.loads(json.dumps(res, default=lambda o: o.tolist()))          # plain data (numpy arrays as lists)


def test_exact_solvers_agree_with_the_reference(small_study):
    """At the reference resolution the fft solver with the banded Taylor series is exact Kirchhoff, so it matches
    the direct float64 sum; float32 adds only round-off; the frozen-v_z fft does not (docs/physics.md §1)."""
    _, st_, res = small_study
    rows = {(s.solver, s.precision, s.resolution, s.realizations): r for s, r in zip(st_, res["settings"])}
    for n in (1, 2):
        assert rows[("fft", "float64", 16, n)]["error_rel_l2"] < TOL["fft_vs_direct64"]
        same = rows[("direct", "float64", 16, n)]
        assert same["error_rel_l2"] < 1e-12 and same["same_as_reference"]
        assert rows[("direct", "float32", 16, n)]["error_rel_l2"] < TOL["direct32"]
        assert rows[("fft0", "float64", 16, n)]["error_rel_l2"] > 100 * TOL["fft_vs_direct64"]
    # the coarse grid is charged for what it misses
    assert rows[("fft", "float64", 8, 1)]["error_rel_l2"] > rows[("fft", "float64", 16, 1)]["error_rel_l2"]


def test_recommendation_meets_target_and_is_fastest(small_study):
    _, _, res = small_study
    rec = res["recommendation"]
    rows = res["settings"]
    ok = [i for i, r in enumerate(rows) if r["error_rel_l2"] <= 1e-3 and not r["same_as_reference"]]
    assert rec["index"] in ok
    assert rows[rec["index"]]["time_s"] == min(rows[i]["time_s"] for i in ok)
    assert rec["index"] in res["pareto"]           # the fastest one meeting a threshold is never dominated
    assert not rows[rec["index"]]["same_as_reference"]
    assert not any(rows[i]["same_as_reference"] for i in res["pareto"])


def test_budget_skips_what_would_overrun():
    cfg = cost.model_config("sinusoid:amplitude=30nm,period=0.8um", "3.2um", 24, illuminant=LASER)
    st_ = cost.ladder(("fft",), (4, 8, 16), (1.0,), (1,))
    res = cost.study(cfg, st_, budget_s=1e-9)
    assert not cfg.random and res["reference"]["realizations"] == 1
    done = [r for r in res["settings"] if r["skipped"] is None]
    assert len(done) == 1 and done[0]["resolution"] == 4            # the first (cheapest) one measures the rate
    assert len(res["skipped"]) == 2
    assert all(r["error_rel_l2"] is None and "budget" in r["skipped"] for r in res["settings"] if r["skipped"])
    assert set(res["pareto"]) == {res["settings"].index(done[0])}


def test_bad_inputs_raise_one_clear_error():
    cfg = cost.model_config("sinusoid:amplitude=30nm,period=0.8um", "3.2um", 16, illuminant=LASER)
    with pytest.raises(WaveopticsError, match="divide"):
        cost.study(cfg, [cost.Setting("fft", 6), cost.Setting("fft", 16)])
    with pytest.raises(WaveopticsError, match="solver"):
        cost.Setting("nufft")
    with pytest.raises(WaveopticsError, match="resolution"):
        cost.Setting("fft", 0)
    with pytest.raises(WaveopticsError, match="budget"):
        cost.study(cfg, [cost.Setting("fft", 8)], budget_s=-1)
    with pytest.raises(WaveopticsError, match="surface model"):
        cost.model_config("fractal:sigma=1nm")
    with pytest.raises(WaveopticsError, match="key=value"):
        cost.parse_model("gaussian:sigma")


def test_cli_cost(tmp_path):
    out = tmp_path / "c"
    args = ["cost", "--generator", "sinusoid:amplitude=30nm,period=0.8um",
            "--size", "3.2um", "--samples", "16", "--resolutions", "4,8", "--solvers", "fft,direct",
            "--precisions", "float32", "--illuminant", LASER, "--target-error", "0.5", "--json", "-o", str(out)]
    rc, stdout, stderr, _ = run_cli(args)
    assert rc == 0, stderr
    res = json.loads(stdout)
    assert {"reference", "settings", "pareto"} <= set(res)
    assert {"solver", "resolution", "wavelengths", "precision", "error_rel_l2", "error_albedo", "delta_e2000",
            "time_s"} <= set(res["settings"][0])
    assert all((out / f).is_file() for f in cost.FILES)
    assert (out / "cost.png").read_bytes()[:4] == b"\x89PNG"
    rc, _, stderr, _ = run_cli(args)
    assert rc == 2 and "already exists" in stderr
    rc, _, stderr, _ = run_cli(args[:-3] + ["--resolutions", "5,8"])
    assert rc == 2 and len(stderr.strip().splitlines()) == 1 and "divide" in stderr


def test_default_fft_reference_agrees_with_the_direct_reference(small_study):
    """The default reference (fft, float64) and the independent direct-sum reference rank the ladder alike: every
    rung's relative L2 error differs by no more than the fft reference's own error (≤ 1e-8 of the lobe), so the same
    rungs meet a target (which of them is fastest is a timing, compared in docs/cost-defaults.md)."""
    cfg, st_, res_direct = small_study
    res_fft = cost.study(cfg, st_, target_error=1e-3)
    assert res_fft["reference"]["solver"] == "fft" and res_direct["reference"]["solver"] == "direct"
    meet = {"fft": set(), "direct": set()}
    for i, (a, b) in enumerate(zip(res_fft["settings"], res_direct["settings"])):
        if a["same_as_reference"] or b["same_as_reference"]:
            continue
        assert abs(a["error_rel_l2"] - b["error_rel_l2"]) < TOL["fft_vs_direct64"]
        if a["error_rel_l2"] <= 1e-3:
            meet["fft"].add(i)
        if b["error_rel_l2"] <= 1e-3:
            meet["direct"].add(i)
    assert meet["fft"] == meet["direct"] and meet["fft"]
