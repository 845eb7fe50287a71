"""Data of docs/cli.md (docs/data/cli.json; prose in docs/templates/cli.md): every command and option of the command
line, with units and defaults, read from the parsers themselves (tests/test_generated_docs.py checks that the data
and the page are current)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from waveoptics.cli import build_parser
from waveoptics.cli._options import OPTIONS, REMOVED_IN, RENAMED

sys.path.insert(0, str(Path(__file__).resolve().parent))

#: command-line option → scene-file key (docs/planning.md) and library field, where they differ in name
SCENE_KEYS = [
    ("--material", "materials.material (or materials.ior)", "SimulationRequest.material"),
    ("--micro-alpha", "materials.roughness", "SimulationRequest.micro_alpha"),
    ("--ndf", "materials.ndf", "SimulationRequest.ndf"),
    ("--kd", "materials.diffuse_albedo", "SimulationRequest.kd"),
    ("--nano", "materials.nano.statistics / generator", "SimulationRequest.nano"),
    ("--surface", "materials.nano.file (path, spacing, units, channel)", "SimulationRequest.surface"),
    ("--diffraction", "materials.diffraction", "SimulationRequest.diffraction"),
    ("--illuminant", "lights.spd", "SimulationRequest.illuminant"),
    ("--incident", "lights.directions_deg", "SimulationRequest.incident_deg"),
    ("--delta-e", "accuracy.delta_e", "SimulationRequest.delta_e"),
    ("--resolution", "output.resolution", "SimulationRequest.resolution"),
    ("--sphere-size", "output.sphere_size", "—"),
]


def _commands(parser, prefix=()):
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sp in a.choices.items():
                words = prefix + (name,)
                if any(isinstance(b, argparse._SubParsersAction) for b in sp._actions):
                    yield from _commands(sp, words)
                else:
                    yield " ".join(words), sp


def _option(a) -> dict | None:
    """One row of a command's option table: what the parser says about argument *a*."""
    if a.help == argparse.SUPPRESS or "--help" in a.option_strings:
        return None
    if a.choices:
        value = "{" + ",".join(map(str, a.choices)) + "}"
    elif a.nargs == 0:
        value = "(flag)"
    else:
        value = a.metavar or a.dest.upper()
    default = None if a.default in (None, False, argparse.SUPPRESS, []) or a.nargs == 0 else str(a.default)
    return {"flags": list(a.option_strings), "name": a.metavar or a.dest, "value": value, "default": default,
            "required": bool(a.required), "help": a.help or ""}


def compute() -> dict:
    """Everything docs/cli.md shows, read from the parsers and the shared option vocabulary."""
    return {
        "options": [{"flag": o.flag, "metavar": o.metavar or "", "unit": o.unit, "meaning": o.meaning}
                    for o in sorted(OPTIONS.values(), key=lambda o: o.flag)],
        "removed_in": REMOVED_IN,
        "renamed": [{"command": cmd, "old": old, "new": new} for (cmd, old), new in sorted(RENAMED.items())],
        "scene_keys": [{"option": f, "scene": k, "field": fld} for f, k, fld in SCENE_KEYS],
        "commands": [{"name": name, "description": p.description or "",
                      "options": [r for r in (_option(a) for a in p._actions) if r]}
                     for name, p in _commands(build_parser())],
    }


def main() -> None:
    import make_docs

    make_docs.main(["cli"])


if __name__ == "__main__":
    main()
