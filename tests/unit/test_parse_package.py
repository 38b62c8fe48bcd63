"""The front end moved to iec2kmod.parse (issue 24); code written against
the old names (iec2kmod.frontend.run, iec2kmod.parser.parse_source, ...)
gets the same module objects, so a monkeypatch on one is seen through the
other."""

import importlib
import subprocess
import sys


def test_old_names_are_the_moved_modules():
    for name in ("frontend", "parser", "stfast", "literals"):
        old = importlib.import_module(f"iec2kmod.{name}")
        new = importlib.import_module(f"iec2kmod.parse.{name}")
        assert old is new, name
    from iec2kmod import frontend
    from iec2kmod.frontend import collect_files, run
    from iec2kmod.parse import frontend as moved
    assert frontend is moved and run is moved.run and collect_files is moved.collect_files


def test_old_names_in_a_fresh_interpreter():
    """Importing by the old name first (no iec2kmod.parse import before)."""
    code = ("import iec2kmod.frontend as f, iec2kmod.literals as lit, sys\n"
            "assert f.__name__ == 'iec2kmod.parse.frontend', f.__name__\n"
            "assert sys.modules['iec2kmod.parse.frontend'] is f\n"
            "assert lit.classify('16#FF')[1] == 255\n"
            "print('ok')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr


def test_unknown_attribute_is_an_attribute_error():
    import iec2kmod
    try:
        iec2kmod.no_such_module  # noqa: B018
    except AttributeError as exc:
        assert "no_such_module" in str(exc)
    else:
        raise AssertionError("iec2kmod.no_such_module did not raise")
