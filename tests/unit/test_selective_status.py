"""plc-manager status shows the per-task counts of selectively executed
blocks (IEC_A_SEL_EVALUATED / IEC_A_SEL_SKIPPED, sent by the kernel only for
tasks that ran selective blocks); the attribute list matches the kernel's
enum (kmod_templates/kernel/iec_nl.h)."""

import re
from pathlib import Path

from plc_manager import netlink
from plc_manager.cli import status_json, status_text

ROOT = Path(__file__).resolve().parents[2]


def _status(sel):
    tasks = [netlink.Task(name="fast", resource="main", state="running", interval_ns=2_000_000,
                          priority=1, last_cpu=0, cycles=1000, overruns=0, faults=0,
                          exec_min_ns=1000, exec_avg_ns=2000, exec_max_ns=3000,
                          latency_avg_ns=100, latency_max_ns=200, histogram=[],
                          sel_evaluated=sel[0], sel_skipped=sel[1]),
             netlink.Task(name="slow", resource="main", state="running", interval_ns=10_000_000,
                          priority=2, last_cpu=0, cycles=100, overruns=0, faults=0,
                          exec_min_ns=1000, exec_avg_ns=2000, exec_max_ns=3000,
                          latency_avg_ns=100, latency_max_ns=200, histogram=[])]
    return netlink.Status(abi=1, configuration="c", module="iec_c_config", source_hash="s",
                          interface_hash="i", now_ns=0, forced=0,
                          resources=[netlink.Resource("main", "iec_c_r_main", 0, tasks)],
                          slots=[])


def test_status_shows_selective_counts():
    text = status_text(_status((250, 3750)))
    line = next(ln for ln in text.splitlines() if ln.startswith("main.fast") and "93.8" in ln)
    assert re.search(r"main\.fast\s+250\s+3750\s+93\.8", line), text
    assert "BLOCKS EVALUATED" in text
    assert not any(ln.startswith("main.slow") and "93" in ln for ln in text.splitlines())
    js = status_json(_status((250, 3750)))
    t = js["resources"][0]["tasks"][0]
    assert (t["sel_evaluated"], t["sel_skipped"]) == (250, 3750)


def test_plain_status_has_no_selective_table():
    st = _status((None, None))
    assert "BLOCKS EVALUATED" not in status_text(st)


def test_attribute_order_matches_the_kernel():
    text = (ROOT / "kmod_templates" / "kernel" / "iec_nl.h").read_text()
    body = text[text.index("IEC_A_UNSPEC"):text.index("__IEC_A_MAX")]
    kernel = re.findall(r"\b(IEC_A_\w+),", body)
    assert [n for n, _ in netlink.ATTRIBUTES] == kernel
