"""Differential tier: random valid projects (progen.py) run in every engine
available -- the C simulator, the C simulator under ASan+UBSan, the C
simulator with selective execution (`sim --selective`: skipping blocks
must be invisible) and, once `iec2kmod sim --engine interp` exists, the
reference interpreter -- must give identical traces (faults included).  300 projects on a fixed seed, 100
cycles each, in batches of 20 projects per simulator build on 2 processes
(bodies 0.6 of the benchmark's default size, to stay within the CI budget).

Reproduce or widen: python3 benchmarks/fuzz_diff.py --count 300 --seed 20261123 --size 0.6
(--unit SEED reruns one project, --keep DIR minimises what fails)."""

from __future__ import annotations

import collections
import os
import time

import pytest

import difftest

pytestmark = pytest.mark.execution

SEED = 20261123
COUNT = int(os.environ.get("IEC2KMOD_FUZZ_COUNT", "300"))
SIZE = 0.6          # statements per body relative to the benchmark's default
# every construct below must be reached by the campaign (a generator that
# silently stopped producing one would make the tier pass for nothing)
MUST_REACH = {
    "fb_external_depth3", "external_array", "external_struct", "external_string",
    "external_const", "fb_inout", "function_inout", "array_multidim", "array_of_fb", "struct",
    "enum", "subrange", "std_CONCAT", "std_MID", "std_REPLACE", "std_FIND", "case", "case_enum",
    "for_down", "for_variable_step", "for_const_step", "while", "repeat", "exit", "return",
    "il_body", "il_deferred", "il_jump", "il_CALC", "il_fb_operators", "event_task",
    "several_resources", "several_tasks", "connection_in_global", "connection_out_direct",
    "located_I", "located_Q", "located_M", "var_constant", "var_temp", "std_fb_TON",
    "std_fb_TOF", "std_fb_TP", "std_fb_CTUD", "std_fb_R_TRIG", "std_fb_F_TRIG", "std_fb_SR",
    "std_fb_RS", "fuzzy_real", "edge_input", "user_function", "global_constant",
    "fb_inout_instance", "sfc", "sfc_simultaneous", "sfc_divergence", "sfc_priority",
    "sfc_il_condition", "sfc_il_action", "sfc_step_t", "sfc_variable_action", "sfc_q_none",
    "sfc_q_N", "sfc_q_R", "sfc_q_S", "sfc_q_P", "sfc_q_P0", "sfc_q_P1", "sfc_q_L", "sfc_q_D",
    "sfc_q_SD", "sfc_q_DS", "sfc_q_SL",
    "fn_form_MOD", "fn_form_bitwise", "real_literal_context", "fb_array_call",
    "function_eno", "function_eno_out",
    "named_const_bound", "named_const_case", "named_const_from_const",
    "named_const_external_bound", "continue_for", "continue_while", "continue_case",
    # boundary values (issue 29): type limits and neighbours in literals and
    # input traces, comparisons of unsigned types
    "boundary_int", "boundary_bit", "boundary_real", "boundary_time", "boundary_string",
    "boundary_input", "boundary_compare_unsigned",
}


def test_generated_projects_agree():
    engines = difftest.available_engines()
    assert "c" in engines and "sanitize" in engines
    seeds = [difftest.unit_seed(SEED, i) for i in range(COUNT)]
    t0 = time.time()
    results = difftest.campaign(seeds, engines, jobs=2, batch=20, cycles=100, size=SIZE)
    dt = time.time() - t0
    assert len(results) == COUNT >= 300 or "IEC2KMOD_FUZZ_COUNT" in os.environ
    reached = set().union(*(r.features for r in results))
    missing = MUST_REACH - reached
    assert not missing, f"the generator no longer reaches: {sorted(missing)}"
    if "selective" in engines:
        # the selective engine must have skipped blocks, or the comparison
        # proved nothing about skipping
        ev = sum(r.selective[0] for r in results)
        sk = sum(r.selective[1] for r in results)
        some = sum(1 for r in results if r.selective[1])
        assert some >= COUNT // 10 and sk >= 0.05 * (ev + sk), \
            f"the selective engine skipped {sk} of {ev + sk} blocks in {some} projects"
    bad = [r for r in results if not r.ok]
    kinds = collections.Counter(k for r in bad for k, _, _ in r.problems)
    report = [f"{len(bad)} of {len(results)} projects failed ({dict(kinds)}) "
              f"with engines {','.join(engines)} in {dt:.0f} s:"]
    for r in bad[:15]:
        for kind, eng, text in r.problems[:2]:
            first = (text or "").strip().splitlines()[0][:400] if text else ""
            report.append(f"  seed {r.seed}: {kind} [{eng}] {first}")
    report.append("minimise one: python3 benchmarks/fuzz_diff.py --unit SEED --keep /tmp/found")
    assert not bad, "\n".join(report)
