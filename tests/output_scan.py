"""The output promise of issue 34, as a scanner every test that writes outputs can run over its directory.

No output file holds a negative or non-finite BRDF or radiance:

* a spectral EXR (``spectralLayoutVersion``; BRDF, reflectance or radiance per wavelength): every value finite, >= 0;
* an RGB EXR (channels R, G, B): every value finite; a negative component only where the file says that colours lie
  outside its space's gamut (header ``waveoptics_out_of_gamut``), with the count of such pixels it states;
* any other EXR channel (heights, ΔE maps): finite where the file is not a height field (a height field's NaN is its
  mask);
* JSON: every number finite; a value under a key naming a BRDF, an albedo, a radiance or a reflectance is >= 0 unless
  the key is an RGB one (linear RGB keeps out-of-gamut colours, stated beside them in ``out_of_gamut``).
"""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np

from waveoptics import io as wio

#: JSON keys whose numbers are BRDFs, albedos, radiances or reflectances (never negative)
NON_NEGATIVE_KEY = re.compile(r"(^|_)(brdf|albedo|albedos|radiance|reflectance|f)($|_)", re.IGNORECASE)
RGB_KEY = re.compile(r"rgb|srgb|colour|color", re.IGNORECASE)


def _exr_problems(path: Path) -> list[str]:
    chans, header = wio.read_exr(path)
    out = []
    spectral = "spectralLayoutVersion" in header
    gamut = header.get("waveoptics_out_of_gamut")
    names = set(chans)
    for name, arr in chans.items():
        a = np.asarray(arr, dtype=float)
        if a.ndim == 3 and a.shape[-1] == 3 and name.upper() in ("RGB", "BGR"):
            rgb = True
        else:
            rgb = name in ("R", "G", "B")
        if name == "Z" or header.get("units") is not None and not spectral and not rgb:
            continue   # a height field: NaN marks its mask
        if not np.all(np.isfinite(a)):
            out.append(f"{path.name}: channel {name} holds a non-finite value")
            continue
        if a.size and a.min() < 0:
            if spectral or not rgb:
                out.append(f"{path.name}: channel {name} holds {a.min()!r} < 0")
            elif gamut is None:
                out.append(f"{path.name}: RGB channel {name} holds {a.min()!r} < 0 and the file does not say its "
                           "colours leave the gamut")
    if gamut is not None and ({"R", "G", "B"} <= names or any(n.upper() == "RGB" for n in names)):
        if {"R", "G", "B"} <= names:
            stack = np.stack([np.asarray(chans[c], dtype=float) for c in "RGB"], axis=-1)
        else:
            stack = np.asarray(next(v for n, v in chans.items() if n.upper() == "RGB"), dtype=float)
        pixels = int((stack.reshape(-1, 3) < 0).any(axis=1).sum())
        if not str(gamut).startswith(f"{pixels} of "):
            out.append(f"{path.name}: states {gamut!r} but {pixels} pixels have a negative component")
    return out


def _json_problems(path: Path) -> list[str]:
    out = []

    def bad(token):
        out.append(f"{path.name}: non-finite number {token}")
        return 0.0

    data = json.loads(path.read_text(), parse_constant=bad)

    def walk(x, key, where, rgb):
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, str(k), f"{where}.{k}", rgb or bool(RGB_KEY.search(str(k))) or k == "out_of_gamut")
        elif isinstance(x, list):
            for i, v in enumerate(x):
                walk(v, key, f"{where}[{i}]", rgb)
        elif isinstance(x, float):
            if not math.isfinite(x):
                out.append(f"{path.name}{where}: {x}")
            elif x < 0 and NON_NEGATIVE_KEY.search(key) and not rgb:
                out.append(f"{path.name}{where}: {x} < 0")
    walk(data, "", "", False)
    return out


def scan_outputs(root) -> list[str]:
    """Problems (empty when none) of every EXR and JSON file under *root* (hidden staging files excluded)."""
    problems = []
    for p in sorted(Path(root).rglob("*")):
        if p.name.startswith(".") or any(part.startswith(".") for part in p.relative_to(root).parts[:-1]):
            continue
        if p.suffix.lower() == ".exr":
            problems += _exr_problems(p)
        elif p.suffix.lower() == ".json":
            problems += _json_problems(p)
    return problems


def count_outputs(root) -> int:
    return sum(1 for p in Path(root).rglob("*") if p.suffix.lower() in (".exr", ".json") and not p.name.startswith("."))
