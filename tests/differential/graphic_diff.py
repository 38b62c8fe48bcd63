"""Runs a graphic_gen project and its referee in one engine and compares
them (issue 28): the XML through iec2kmod/plcopen, the ST as written by
the generator, the same input trace, every output after every cycle."""

from __future__ import annotations

from pathlib import Path

from iec2kmod import interp, sim
from iec2kmod.parse import frontend

STEP = 10_000_000


def _run(path: Path, p, engine, workdir: Path):
    res = frontend.run([str(path)], use_cache=False)
    if not res.ok:
        return None, "\n".join(d.format() for d in res.diags.errors)[:2000]
    trace = workdir / f"{path.stem}.inputs.csv"
    trace.write_text("".join(f"{(c - 1) * STEP}ns,res.inst.{n},{v}\n" for c, n, v in p.inputs))
    watch = [f"res.inst.{o}" for o in p.outputs]
    end = STEP * (p.cycles - 1)
    try:
        if engine == "interp":
            out = interp.run(res.project, end, watch=watch, inputs=str(trace))
        else:
            out = sim.run(res.project, end, watch=watch, inputs=str(trace),
                          build_dir=workdir / "sim")
    except (interp.InterpError, sim.SimError, sim.InternalError) as exc:
        return None, f"{engine}: {exc}"
    return [out.values_at(k * STEP) for k in range(p.cycles)], None


def compare(p, engine: str, workdir: Path) -> str | None:
    """None when the translation and the referee agree, else what differs."""
    workdir.mkdir(parents=True, exist_ok=True)
    xml = workdir / "plc.xml"
    ref = workdir / "ref.st"
    xml.write_text(p.xml)
    ref.write_text(p.st)
    got, err = _run(xml, p, engine, workdir)
    if err:
        return f"the XML project: {err}"
    want, err = _run(ref, p, engine, workdir)
    if err:
        return f"the referee (a generator bug): {err}"
    for k, (a, b) in enumerate(zip(got, want)):
        if a != b:
            diff = {n: (a.get(n), b.get(n)) for n in b if a.get(n) != b.get(n)}
            return f"after cycle {k + 1}: (translation, referee) {diff}"
    return None
