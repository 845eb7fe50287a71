"""``waveoptics info``: versions, OpenCL platforms and devices."""
from __future__ import annotations

import platform as _platform


from ._common import add_common, emit


def register(sub):
    p = sub.add_parser("info", help="show versions and OpenCL platforms/devices",
                       description="Package version, OpenCL platforms and devices (compute units, fp64, "
                                   "max work-group size), PoCL version and library versions.")
    add_common(p)
    p.set_defaults(func=run)


def gather(device=None) -> dict:
    """Everything ``info`` reports, as plain data."""
    from importlib import metadata

    from .. import __version__
    from .. import runtime
    import numpy
    import pyopencl

    # colour-science's version from its installed metadata: importing it (for colour.__version__) loads its
    # plotting, matplotlib and pandas, 1.5-2 s of the command
    try:
        colour_version = metadata.version("colour-science")
    except metadata.PackageNotFoundError:
        colour_version = None
    data = {
        "waveoptics": __version__,
        "python": _platform.python_version(),
        "numpy": numpy.__version__,
        "pyopencl": pyopencl.VERSION_TEXT,
        "colour": colour_version,
        "pocl": runtime.pocl_version(),
        "kernel_dir": str(runtime.kernel_dir()),
        **runtime.describe(),
    }
    try:
        dev = runtime.select_device(device)
        data["selected_device"] = f"{dev.platform.name.strip()} {dev.name.strip()}"
        data["selected_device_fp64"] = runtime.has_fp64(dev)
    except ValueError as exc:
        data["selected_device"] = None
        data["error"] = str(exc)
    return data


def run(args):
    data = gather(args.device)
    if args.json:
        emit(args, data)
        return 0
    lines = [f"waveoptics {data['waveoptics']} (python {data['python']}, numpy {data['numpy']}, "
             f"pyopencl {data['pyopencl']}, colour {data['colour']})",
             f"kernels: {data['kernel_dir']}"]
    if not data["platforms"]:
        lines.append("OpenCL: no platform found")
    for p in data["platforms"]:
        lines.append(f"platform: {p['name']} ({p['version']})")
        for d in p["devices"]:
            lines.append(f"  device: {d['name']} [{d['type']}], {d['compute_units']} compute units, "
                         f"fp64 {'yes' if d['fp64'] else 'no'}, max work-group {d['max_work_group_size']}")
    if data.get("selected_device"):
        lines.append(f"selected: {data['selected_device']} (fp64 {'yes' if data['selected_device_fp64'] else 'no'})")
    print("\n".join(lines))
    if data.get("error"):
        raise ValueError(data["error"])
    return 0
