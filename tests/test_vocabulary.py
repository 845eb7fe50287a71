"""One vocabulary across the command line (issue 19): an option name means one quantity in every command — the
same help (its shared meaning first), unit, metavar and type — renamed options keep working for one release with
a one-line deprecation warning (docs/cli.md, generated from the parsers, is checked in test_generated_docs.py)."""
import argparse
from collections import defaultdict

import pytest

from cli_helpers import run_cli
from waveoptics.cli import build_parser, command_parser
from waveoptics.cli._options import OPTIONS, RENAMED


def _walk(parser, prefix=()):
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sp in a.choices.items():
                yield from _walk(sp, prefix + (name,))
        else:
            yield " ".join(prefix), a


def _shared_options():
    by_flag = defaultdict(list)
    for cmd, a in _walk(build_parser()):
        if a.help == argparse.SUPPRESS:
            continue
        for flag in a.option_strings:
            if flag.startswith("--") and flag != "--help":
                by_flag[flag].append((cmd, a))
    return {f: v for f, v in by_flag.items() if len({c for c, _ in v}) > 1}


@pytest.mark.parametrize("flag", sorted(_shared_options()))
def test_an_option_means_one_quantity_in_every_command(flag):
    uses = _shared_options()[flag]
    if flag in OPTIONS:
        o = OPTIONS[flag]
        for cmd, a in uses:
            assert a.help.startswith(o.meaning), (cmd, flag, a.help)
            if o.metavar and not a.choices and a.nargs != 0:
                assert a.metavar == o.metavar, (cmd, flag, a.metavar)
            if o.type is not None and a.nargs != 0:
                assert a.type is o.type, (cmd, flag, a.type)
    else:   # defined by one shared helper: identical everywhere
        first = uses[0][1]
        for cmd, a in uses[1:]:
            assert (a.help, a.metavar, a.type, a.choices, a.default) == \
                (first.help, first.metavar, first.type, first.choices, first.default), (cmd, flag)


def test_no_flag_is_the_old_name_of_another():
    """A renamed flag is not reused for something else in the command that renamed it."""
    parser = build_parser()
    for (cmd, old), new in RENAMED.items():
        p = command_parser(parser, cmd)
        actions = {f: a for a in p._actions for f in a.option_strings}
        assert actions[old].help == argparse.SUPPRESS, (cmd, old)
        assert actions[old].dest == actions[new].dest, (cmd, old, new)


@pytest.mark.parametrize("argv, old, new", [
    (["brdf", "--model", "microfacet", "--ior", "1.5", "--alpha", "0.2", "--incident", "30", "--outgoing", "30,180",
      "--wavelength", "550", "--json"], "--wavelength", "--wavelengths"),
    (["brdf", "--model", "microfacet", "--ior", "1.5", "--alpha", "0.2", "--incident", "30", "--outgoing", "30,180",
      "--diffuse", "oren-nayar", "--kd", "0.5", "--sigma", "20", "--json"], "--sigma", "--diffuse-sigma"),
])
def test_renamed_options_still_work_with_one_line_warning(argv, old, new):
    rc, out, err, _ = run_cli(argv)
    assert rc == 0, err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "deprecated" in lines[0] and old in lines[0] and new in lines[0], err
    rc2, out2, err2, _ = run_cli([new if a == old else a for a in argv])
    assert rc2 == 0 and out2 == out and err2 == ""


def test_surface_generate_old_model_flag(tmp_path):
    rc, out, err, _ = run_cli(["surface", "generate", "--model", "flat", "--samples", "8", "-o",
                               str(tmp_path / "f.npz")])
    assert rc == 0 and "--model is deprecated" in err and "--generator" in err
    rc, out, err, _ = run_cli(["surface", "generate", "--samples", "8", "-o", str(tmp_path / "g.npz")])
    assert rc == 2 and "--generator" in err


def test_the_correlation_length_is_corr_length_and_old_T_warns_once():
    """One name (corr_length) in nano text, cost's generator text and the sweep's nano.KEY; the old ``T=`` still
    parses to the same value, with one RenamedWarning naming the new spelling."""
    import warnings

    from waveoptics.distributed.sweep import parse_vary
    from waveoptics.errors import RenamedWarning
    from waveoptics.request import NANO_ALIASES, NANO_RENAMED, parse_nano
    from waveoptics.study.accuracy_cost import parse_model

    with warnings.catch_warnings():
        warnings.simplefilter("error")   # the one name parses without a warning
        new = parse_nano("gaussian:sigma=5nm,corr_length=1um")
        assert parse_nano("exponential:sigma=5nm,corr=1um") == ("exponential", new[1])
        new_model = parse_model("gaussian:sigma=5nm,corr_length=1um")
    assert new == ("gaussian", {"sigma": 5e-9, "corr_length": 1e-6})
    for parse, text, expected in ((parse_nano, "gaussian:sigma=5nm,T=1um", new),
                                  (parse_model, "gaussian:sigma=5nm,T=1um", new_model),
                                  (parse_vary, "nano.T=1um,2um", ("nano.T", [1e-6, 2e-6]))):
        with pytest.warns(RenamedWarning) as caught:
            assert parse(text) == expected
        assert len(caught) == 1 and "T= is deprecated" in str(caught[0].message) and "corr_length=" in str(
            caught[0].message)
    # the alias tables point one way: every target is a canonical name, never itself an alias
    for table in (NANO_ALIASES, NANO_RENAMED):
        assert not set(table.values()) & (set(NANO_ALIASES) | set(NANO_RENAMED))


def test_old_T_in_nano_text_is_one_cli_warning_line(tmp_path):
    rc, out, err, _ = run_cli(["brdf", "--model", "twoscale", "--material", "Au", "--alpha", "0.1", "--nano",
                               "gaussian:sigma=5nm,T=1um", "--incident", "30", "--outgoing", "30,180",
                               "--wavelengths", "550", "--resolution", "16"])
    lines = [ln for ln in err.splitlines() if "T= is deprecated" in ln]
    assert rc == 0 and len(lines) == 1 and "corr_length=" in lines[0], err



def test_no_renormalize_is_accepted_with_one_deprecation_line(tmp_path):
    """--no-renormalize (the old way to keep the PSD as given) is now the default: accepted, one warning line."""
    rc, out, err, caught = run_cli(["surface", "generate", "--generator", "gaussian", "--sigma", "5nm",
                                    "--corr-length", "1um", "--size", "8um", "--samples", "32", "--no-renormalize",
                                    "-o", str(tmp_path / "h.npz")])
    assert rc == 0 and (tmp_path / "h.npz").is_file()
    notes = [w for w in caught + err.splitlines() if "--no-renormalize" in w]
    assert notes and all("\n" not in n.strip() for n in notes) and "--renormalize" in notes[0]
