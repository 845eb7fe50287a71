"""OpenCL runtime: device choice, build-once cache, build-failure reporting, packaging of kernels."""
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from waveoptics import runtime
from waveoptics.cli import main
from waveoptics.errors import NoOpenCLError, WaveopticsError


def test_kernel_dir_has_sources():
    assert (runtime.kernel_dir() / "fresnel.cl").is_file()
    assert "#include" in runtime.kernel_source("fresnel.cl")


def test_program_built_once_per_context_and_options(rt):
    before = runtime.program_cache_size()
    p1 = runtime.build_program(rt, "fresnel.cl", runtime.build_options(np.float32))
    p2 = runtime.build_program(rt, "fresnel.cl", runtime.build_options(np.float32))
    assert p1 is p2
    after_one = runtime.program_cache_size()
    assert after_one - before <= 1
    runtime.build_program(rt, "fresnel.cl", runtime.build_options(np.float32, ("-DWO_UNUSED_SWITCH=1",)))
    assert runtime.program_cache_size() == after_one + 1


def test_build_failure_names_file_and_shows_log(rt, tmp_path, monkeypatch):
    (tmp_path / "broken.cl").write_text("__kernel void k(__global float *x) { x[0] = undefined_symbol; }\n")
    for h in runtime.kernel_dir().glob("*.h"):
        (tmp_path / h.name).write_text(h.read_text())
    monkeypatch.setattr(runtime, "kernel_dir", lambda: tmp_path)
    with pytest.raises(WaveopticsError, match=r"kernels/broken.cl failed") as exc:
        runtime.build_program(rt, "broken.cl")
    assert "undefined_symbol" in str(exc.value)


def test_device_selection_by_substring_and_env(rt, monkeypatch):
    label = rt.device.name.strip()[:6]
    assert runtime.select_device(label).name == rt.device.name
    monkeypatch.setenv("WAVEOPTICS_DEVICE", label)
    assert runtime.select_device().name == rt.device.name
    assert runtime.select_device("0:0") is not None
    with pytest.raises(NoOpenCLError, match="no OpenCL device matches 'no-such-device'"):
        runtime.select_device("no-such-device")


def test_fp64_detection_is_reported(rt):
    assert isinstance(rt.fp64, bool)
    assert rt.real_dtype("float32") == np.float32
    with pytest.raises(WaveopticsError, match="precision"):
        rt.real_dtype("float16")


def test_no_platform_gives_install_hint_and_exit_2(monkeypatch, capsys):
    monkeypatch.setattr(runtime, "platforms", lambda: [])
    with pytest.raises(NoOpenCLError, match="pocl-opencl-icd"):
        runtime.select_device()
    assert main(["info"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pocl-opencl-icd" in err[0] and "Traceback" not in err[0]


def test_info_json(capsys):
    import json

    assert main(["info", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["platforms"] and data["platforms"][0]["devices"][0]["compute_units"] >= 1
    assert {"waveoptics", "numpy", "pyopencl", "colour", "pocl"} <= set(data)


@pytest.mark.slow
def test_wheel_carries_the_kernels_and_runs_one(tmp_path):
    """The wheel carries the top-level kernels/ inside the package (hatch force-include), and the package imported
    from the unpacked wheel, away from the checkout, builds and runs a kernel (Fresnel at normal incidence against
    ((n − 1)/(n + 1))², written here)."""
    root = Path(runtime.__file__).resolve().parent.parent
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(tmp_path), str(root)], check=True)
    wheel = next(tmp_path.glob("waveoptics-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    assert "waveoptics/kernels/fresnel.cl" in names and "waveoptics/kernels/wo_common.h" in names
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    if not runtime.opencl_available():
        pytest.skip(runtime.INSTALL_HINT)
    code = ("import numpy as np, waveoptics, waveoptics.runtime as r, waveoptics.materials.fresnel as f;"
            "print(waveoptics.__file__); print(r.kernel_dir());"
            "Rs, Rp, R = f.F_sp_cl(np.array([1.0]), np.array([1.5+0j]));"
            "print(float(np.asarray(R).ravel()[0]))")
    out = subprocess.run([sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, {str(site)!r}); " + code],
                         cwd=tmp_path, capture_output=True, text=True, check=True).stdout.split()
    assert out[0].startswith(str(site)) and out[1].startswith(str(site))
    assert abs(float(out[2]) - 0.04) < 1e-6


def test_each_thread_gets_its_own_kernel_object():
    """program_kernel: the same object on every call of one thread, another object in another thread (a kernel
    object holds its arguments, which threads must not share: OpenCL 1.2 appendix A.2)."""
    import threading

    from waveoptics.runtime import build_options, build_program, get_runtime, program_kernel

    rt = get_runtime()
    prg = build_program(rt, "microfacet.cl", build_options(np.float32, ("-DWO_NDF=0",)))
    mine = program_kernel(prg, "D_eval")
    assert program_kernel(prg, "D_eval") is mine
    other = []
    t = threading.Thread(target=lambda: other.append(program_kernel(prg, "D_eval")))
    t.start()
    t.join()
    assert other[0] is not mine


def test_kernels_called_from_many_threads_at_once_give_the_serial_results():
    """Eight threads evaluating the NDF kernel on arrays of different sizes at once (the argument race of a shared
    kernel object would hand one thread's buffers to another) equal the same calls made one after another, and
    the closed form of Beckmann's D written here (Walter et al. 2007, eq. 25) to float32 rounding. With one
    kernel object shared by all threads (the code before program_kernel) this test aborted the process (SIGABRT
    in PoCL, 3 runs of 3)."""
    from concurrent.futures import ThreadPoolExecutor

    from waveoptics.brdf.opencl import D_cl

    rng = np.random.default_rng(11)
    jobs = []
    for k in range(32):
        n = 50 + 37 * k
        t, p = np.arccos(rng.uniform(0.2, 1.0, n)), rng.uniform(0, 2 * np.pi, n)
        jobs.append((np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1), 0.05 + 0.01 * k))
    serial = [D_cl(m, a, ndf="beckmann") for m, a in jobs]
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)   # threads switch between any two bytecodes: the race, if any, shows
    try:
        with ThreadPoolExecutor(8) as ex:
            threaded = list(ex.map(lambda job: D_cl(job[0], job[1], ndf="beckmann"), jobs * 4))
    finally:
        sys.setswitchinterval(old)
    for got, want in zip(threaded, serial * 4):
        np.testing.assert_array_equal(got, want)
    for (m, a), d in zip(jobs, serial):
        c2 = m[:, 2] ** 2
        ref = np.exp(-(1 - c2) / (c2 * a * a)) / (np.pi * a * a * c2 * c2)
        np.testing.assert_allclose(d, ref, rtol=2e-5, atol=1e-6 * ref.max())
