# SPDX-License-Identifier: MIT
"""The manager's protocols: load, swap, stop, start, and variable access.

load   check the manifest and the kernel release; insert the configuration
       module, the program types, the resources (manifest load_order);
       confirm every slot runs its build; start the tasks.  A failure half
       way removes what was inserted.
swap   in two halves.  Prepare (slow, nothing changes for the tasks): check
       the new program-type modules (interface hash against the running
       slot, kernel release, files) before inserting anything, then insert
       each one with stage=1 (relocation, its init checks it against its
       slot and stages it there).  Perform (quick): one netlink command
       publishes every staged build at once (RCU pointer swap: the next
       cycle of every task runs the new body; then a grace period: every
       cycle running at the swap has ended, no task can still run an old
       body, the old modules' references are dropped); confirm the slots
       run the new builds and a cycle ran them; remove the old modules.
       `swap --prepare` stops after the first half, `swap --publish` does
       the second.  Timed step by step, with the kernel's own clock for
       the publication and for the first cycle of each new body.
stop   stop the tasks; remove the resources (their exit joins the threads),
       clear the GFT, remove the program types and the configuration.

Nothing waits for ever: the kernel bounds every wait for a task (stop,
clear, publication: its wait_ms parameter, 1 s by default, plus four task
periods) and fails with ETIMEDOUT when a task does not come back from its
cycle; the manager then names the task (from the status: how long it has
been inside its cycle) in one line and exits 1.  What such a task may
still run stays loaded (its resource module, the program type it runs).
"""

from __future__ import annotations

import contextlib
import difflib
import errno
import gc
import time
from pathlib import Path
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from . import kmod, values
from .errors import NotLoaded, PLCError, UsageError
from .netlink import MAX_FORCES, Client, KernelError, Status, VarValue
from .project import (Candidate, Project, State, check_module_identity, check_module_kernel,
                      interface_changes, swap_candidates)

Progress = Callable[[str], None]


def _quiet(_msg: str) -> None:
    pass


def _ms(t0: float, t1: float) -> float:
    return (t1 - t0) * 1000.0


def connect(what: str = "") -> Client:
    try:
        return Client()
    except NotLoaded:
        if what:
            raise NotLoaded(f"nothing is loaded: {what} needs a running configuration "
                            f"(plc-manager load DIR first)") from None
        raise


def running_state(st: Status) -> Optional[State]:
    """The saved state of the running configuration, if it is the one the
    kernel runs."""
    s = State.load(st.configuration)
    if s is None:
        return None
    if s.interface_hash != st.interface_hash or s.source_hash != st.source_hash:
        return None
    return s


def _stuck(c: Client) -> str:
    """The tasks inside a cycle for longer than a second, as the kernel
    reports them: 'task r.t (inside one cycle for 1234 ms)'."""
    try:
        st = c.status()
    except PLCError:
        return ""
    late = sorted((t for t in st.tasks() if (t.in_cycle_ns or 0) >= 100_000_000),
                  key=lambda t: -(t.in_cycle_ns or 0))
    return ", ".join(f"task {t.path} (inside one cycle for {t.in_cycle_ns // 1_000_000} ms)"
                     for t in late)


def _kernel_call(c: Client, what: str, fn, *args):
    """A netlink command; ETIMEDOUT (a task did not come back within the
    kernel's bound) becomes one line naming the task."""
    try:
        return fn(*args)
    except KernelError as e:
        if e.code != errno.ETIMEDOUT:
            raise
        who = _stuck(c) or "a task"
        raise PLCError(f"{what}: {who} does not come back; the kernel gave up waiting "
                       f"(/sys/module/<configuration module>/parameters/wait_ms); what it may "
                       f"still run stays loaded") from None


def _in_scope(t, resource: Optional[str]) -> bool:
    return resource is None or t.resource.lower() == resource.lower()


def fault_text(t) -> str:
    """'division by zero in Faulty line 15'; a fault of the task itself (the
    watchdog's overruns) has no place; an I/O fault names its channel and no
    line ('I/O device error in io daq.0.0 %IW0 errno 19')."""
    if t.fault_pou in (None, "", "?") and not t.fault_line:
        return f"{t.fault}"
    if not t.fault_line:
        return f"{t.fault} in {t.fault_pou}"
    return f"{t.fault} in {t.fault_pou} line {t.fault_line}"


def fault_facts(st: Status, resource: Optional[str] = None) -> List[str]:
    """One line per task (of *resource*, or of every resource) that is
    stopped on a fault: a fact about the task, not an error of a command."""
    return [f"task {t.path} is stopped on a fault: {fault_text(t)}"
            for t in st.tasks()
            if t.state == "fault" and _in_scope(t, resource)]


def _wait_tasks(c: Client, pred, what: str, timeout: float = 5.0,
                resource: Optional[str] = None, fail_on_fault: bool = True) -> Status:
    """Polls the status until *pred* holds.  A fault of a task in scope
    (*resource*, or every resource) fails a start (*fail_on_fault*); a stop
    waits only for the tasks to leave the running state, whatever the
    state of the others."""
    deadline = time.monotonic() + timeout
    while True:
        st = c.status()
        faults = [t for t in st.tasks() if t.state == "fault" and _in_scope(t, resource)]
        if faults and fail_on_fault:
            t = faults[0]
            raise PLCError(f"task {t.path} stopped on a fault: {fault_text(t)}")
        if pred(st):
            return st
        if time.monotonic() > deadline:
            raise PLCError(f"the tasks did not {what} within {timeout:.0f} s")
        time.sleep(0.005)


# ---------------------------------------------------------------------------
# load / stop / start

@dataclass
class LoadReport:
    configuration: str
    modules: List[Tuple[str, float]] = field(default_factory=list)   # name, ms
    start_ms: Optional[float] = None
    total_ms: float = 0.0
    # where the command's time went, in order: {"project": ms, ...}
    phases: Dict[str, float] = field(default_factory=dict)

    def mark(self, phase: str, t0: float) -> float:
        now = time.perf_counter()
        self.phases[phase] = self.phases.get(phase, 0.0) + _ms(t0, now)
        return now


def _loaded_configurations() -> List[str]:
    try:
        import os
        return sorted(os.listdir("/sys/kernel/iec2kmod"))
    except OSError:
        return []


def load(path: str, start: bool = True, progress: Progress = _quiet) -> LoadReport:
    kmod.require(kmod.CAP_SYS_MODULE, "load")
    t_all = time.perf_counter()
    phases: Dict[str, float] = {}
    proj = Project.open(path)
    t = time.perf_counter()
    phases["open project"] = _ms(t_all, t)
    proj.check_built()
    proj.check_kernel()
    proj.check_modules()
    t2 = time.perf_counter()
    phases["check modules"] = _ms(t, t2)
    from . import io
    if io.check_devices(proj.m):    # the I/O map's devices, before any insert
        t = t2
        t2 = time.perf_counter()
        phases["check devices"] = _ms(t, t2)
    loaded = kmod.loaded()
    running = _loaded_configurations()
    if running:
        raise PLCError(f"configuration {running[0]} is loaded already (one configuration at "
                       f"a time: plc-manager stop first)")
    clash = [n for n in proj.m["load_order"] if n in loaded]
    if clash:
        raise PLCError(f"module {clash[0]} is loaded already (plc-manager stop first)")
    rep = LoadReport(proj.configuration, phases=phases)
    t = rep.mark("loaded modules", t2)
    progress(f"loading {proj.configuration} from {proj.path} "
             f"({len(proj.m['load_order'])} modules)")
    inserted: List[str] = []
    try:
        for name in proj.m["load_order"]:
            t0 = time.perf_counter()
            kmod.insert(str(proj.ko(name)))
            dt = _ms(t0, time.perf_counter())
            inserted.append(name)
            rep.modules.append((name, dt))
            progress(f"  inserted {name:<44} {dt:8.1f} ms")
        t = rep.mark("insert", t)
        with connect() as c:
            st = c.status()
            for pt in proj.m["program_types"]:
                s = st.slot(pt["name"])
                if s is None or s.build_id != pt["build_id"]:
                    raise PLCError(f"slot {pt['name']} does not run build {pt['build_id']}")
            names = {r.name.lower() for r in st.resources}
            for r in proj.m["resources"]:
                if r["name"].lower() not in names:
                    raise PLCError(f"resource {r['name']} did not register")
            t = rep.mark("confirm", t)
            State.create(proj).save()
            t = rep.mark("save state", t)
            if start:
                t0 = time.perf_counter()
                c.start()
                _wait_tasks(c, _all_running, "start")
                rep.start_ms = _ms(t0, time.perf_counter())
                rep.mark("start", t)
                progress(f"  started every task{'':<32} {rep.start_ms:8.1f} ms")
    except BaseException as e:
        if inserted:
            progress(f"  failed: {e}")
            progress("  removing what was inserted")
            _rollback(proj, inserted, progress)
        raise
    rep.total_ms = _ms(t_all, time.perf_counter())
    progress(f"loaded {proj.configuration}: {len(inserted)} modules in "
             f"{rep.total_ms:.0f} ms{'' if start else ' (tasks stopped)'}")
    progress("  " + ", ".join(f"{k} {v:.0f} ms" for k, v in rep.phases.items()))
    return rep


def _all_running(st: Status) -> bool:
    """Every task runs; every periodic one has completed a cycle."""
    return all(t.state == "running" and (t.cycles > 0 or not t.interval_ns)
               for t in st.tasks())


def _rollback(proj: Project, inserted: List[str], progress: Progress) -> None:
    config = proj.m["load_order"][0]
    try:
        if config in inserted:
            unload(config, progress)
        else:
            for name in reversed(inserted):
                kmod.remove(name)
        State.remove(proj.configuration)
    except PLCError as e:
        progress(f"  rollback incomplete: {e}")


def unload(config_module: str, progress: Progress = _quiet) -> List[str]:
    """Stop everything and remove the configuration module and every module
    that uses it: resources first (their exit joins the task threads), then
    the GFT is cleared, then program types, then the configuration.

    Whatever state the tasks are in (running, stopped, stopped on a fault)
    and whatever was left half done (a slot never published, a resource
    never started) does not matter: every module that can go goes.  A task
    that does not come back from its cycle (ETIMEDOUT) keeps loaded only
    what it may still run: its resource module, the program types it runs
    (their slots are cleared one by one: the kernel's grace period of a
    slot waits only for the tasks that run it), and so the configuration;
    the other resources and program types go.  Raises PLCError naming the
    task and what is left loaded, if anything is."""
    removed: List[str] = []
    problems: List[str] = []
    stuck = False

    def kernel(what: str, fn, *args) -> bool:
        nonlocal stuck
        try:
            _kernel_call(c, what, fn, *args)
            return True
        except PLCError as e:
            stuck = True
            if not problems:
                problems.append(str(e))
            progress(f"  {e}")
            return False

    def remove(m: str) -> None:
        t0 = time.perf_counter()
        try:
            kmod.remove(m)
        except kmod.ModuleError as e:
            if e.code == errno.ENOENT:          # gone already
                return
            msg = str(e)
            if e.code in (errno.EWOULDBLOCK, errno.EBUSY):   # a user I/O device held?
                from .iodaemon import holders_hint
                msg += holders_hint(m)
            problems.append(msg)
            progress(f"  could not remove {m}: {msg}")
            return
        removed.append(m)
        progress(f"  removed {m:<45} {_ms(t0, time.perf_counter()):8.1f} ms")

    try:
        with Client() as c:
            kernel("stop", c.stop)
            st = c.status()
            for r in st.resources:
                remove(r.module)
            if not kernel("clear", c.clear):
                # every slot is empty, but the old bodies of the slots a
                # task still inside its cycle runs stay referenced: the
                # others are released slot by slot
                for s in st.slots:
                    with contextlib.suppress(KernelError):
                        c.clear(s.index)
    except NotLoaded:
        pass
    for m in kmod.holders(config_module):
        remove(m)
    remove(config_module)
    if config_module in kmod.loaded():
        left = kmod.holders(config_module) + [config_module]
        gone = f"; removed {', '.join(removed)}" if removed else ""
        again = " (stop again once that cycle has ended)" if stuck else ""
        raise PLCError(f"{problems[0] if problems else 'unload failed'}{gone}; still loaded: "
                       f"{', '.join(left)}{again}")
    return removed


def stop(keep_loaded: bool = False, resource: Optional[str] = None,
         progress: Progress = _quiet) -> None:
    """Stops the tasks (of one resource with *resource*), then unless
    *keep_loaded* or *resource* removes every module.  Tasks stopped on a
    fault are reported (progress), not a reason to refuse: a faulted task is
    idle, its resource can go.  Everything is checked before anything is
    done (capabilities, the resource's name)."""
    if not keep_loaded and not resource:
        kmod.require(kmod.CAP_SYS_MODULE, "stop")
    with connect("stop") as c:
        st = c.status()
        if resource:
            r = _resource(st, resource)
            _kernel_call(c, "stop", c.stop, r.name)
            st = _wait_tasks(c, lambda s: all(t.state != "running" for t in s.tasks()
                                              if _in_scope(t, r.name)),
                             "stop", resource=r.name, fail_on_fault=False)
            for line in fault_facts(st, r.name):
                progress(line)
            progress(f"stopped resource {r.name} ({len(r.tasks)} tasks)")
            return
        try:
            _kernel_call(c, "stop", c.stop)
        except PLCError:
            # a task does not come back from its cycle: with --keep-loaded
            # that is the answer; otherwise unload() stops again and
            # removes everything that task cannot still run
            if keep_loaded:
                raise
        else:
            st = _wait_tasks(c, lambda s: all(t.state != "running" for t in s.tasks()),
                             "stop", fail_on_fault=False)
            for line in fault_facts(st):
                progress(line)
            progress(f"stopped every task of {st.configuration}")
            if keep_loaded:
                return
    config = st.configuration
    # a user I/O device (iec_io_user.c) held by a daemon holds its resource
    # module: say so before removing anything (the tasks are stopped)
    from .iodaemon import holders_hint
    held = [f"{r.module}{hint}" for r in st.resources if (hint := holders_hint(r.module))]
    if held:
        raise PLCError(f"the tasks of {config} are stopped, but nothing is removed: "
                       f"{'; '.join(held)}; then stop again")
    removed = unload(st.module, progress)
    State.remove(config)
    progress(f"removed {len(removed)} modules: nothing of {config} is loaded")


def start(resource: Optional[str] = None, progress: Progress = _quiet) -> None:
    """Starts the tasks that are not running (stopped, or stopped on a
    fault: a start clears the fault) of one resource or of every one, and
    waits until each of them completed a cycle since.  A task in scope that
    faults meanwhile fails the command; other resources' faults are not
    this command's business."""
    with connect("start") as c:
        st = c.status()
        r = _resource(st, resource) if resource else None
        name = r.name if r else None
        # cycles are counted since the load: a started task must add one
        before = {t.path: t.cycles for t in st.tasks() if _in_scope(t, name)}

        def started(s: Status) -> bool:
            return all(t.state == "running" and
                       (t.cycles > before.get(t.path, 0) or not t.interval_ns)
                       for t in s.tasks() if _in_scope(t, name))
        if r:
            c.start(r.name)
            _wait_tasks(c, started, "start", resource=r.name)
            progress(f"started resource {r.name} ({len(r.tasks)} tasks)")
            return
        c.start()
        _wait_tasks(c, started, "start")
        progress(f"started every task of {st.configuration}")


def _resource(st: Status, name: str):
    for r in st.resources:
        if r.name.lower() == name.lower():
            return r
    raise UsageError(f"no resource {name!r} in configuration {st.configuration} "
                     f"(resources: {', '.join(r.name for r in st.resources) or 'none'})")


# ---------------------------------------------------------------------------
# swap

@dataclass
class SwapStep:
    type_name: str
    old_module: Optional[str]
    old_build: Optional[str]
    new_module: str
    new_build: str
    insert_ms: float = 0.0
    confirm_ms: float = 0.0
    first_cycle_ms: Optional[float] = None
    first_cycle_task: Optional[str] = None
    remove_ms: float = 0.0
    publish_ms: float = 0.0          # command to the slot's publication (kernel clock)
    latency_ms: float = 0.0          # command to new body running (or confirmed)
    perform_ms: float = 0.0          # publish command to the publication (kernel clock)
    publication_to_first_ms: Optional[float] = None  # to the new body's first cycle (kernel)
    staged: bool = False             # prepared (inserted with stage=1), not yet published


@dataclass
class SwapReport:
    check_ms: float = 0.0
    steps: List[SwapStep] = field(default_factory=list)
    total_ms: float = 0.0
    restarted: List[str] = field(default_factory=list)     # tasks restarted (--restart)
    prepare_ms: float = 0.0          # checks + inserting the staged builds
    published: bool = False
    # where the command's time went, in order: {"connect": ms, ...}
    phases: Dict[str, float] = field(default_factory=dict)

    def mark(self, phase: str, t0: float) -> float:
        """Records *phase* as lasting from *t0* to now; returns now."""
        now = time.perf_counter()
        self.phases[phase] = self.phases.get(phase, 0.0) + _ms(t0, now)
        return now


def _tasks_running_type(manifest: Optional[dict], type_name: str) -> List[str]:
    """resource.task of every task that runs an instance of the type."""
    if not manifest or "instances" not in manifest:
        return []
    return sorted({f"{i['resource']}.{i['task']}".lower() for i in manifest["instances"]
                   if i["type"].upper() == type_name.upper() and i.get("task")})


def _require_instances(manifest: Optional[dict]) -> None:
    if not (manifest and "instances" in manifest):
        raise UsageError("swap --restart needs the manifest of the running configuration "
                         "(saved by plc-manager load, or beside the new modules) to know "
                         "which tasks run the swapped program types")


def swap(new: str, restart: bool = False, progress: Progress = _quiet,
         prepare_only: bool = False) -> SwapReport:
    """Hot code change of the program types NEW names, in two halves:
    prepare (checks, insert staged) and, unless *prepare_only*, publish.
    *restart*: then restart every task that is stopped on a fault and runs
    an instance of a swapped type (one command from a fault to running
    again: the program instances keep their state), and wait for a cycle of
    each."""
    kmod.require(kmod.CAP_SYS_MODULE, "swap")
    t_cmd = time.perf_counter()
    t_wall = time.time_ns()
    rep = SwapReport()
    with connect("swap") as c:
        st = c.status(slots_only=True)
        state = running_state(st)
        if any(s.staged for s in st.slots):
            raise UsageError("a swap is prepared already (staged: " +
                             ", ".join(f"{s.type_name} {s.staged}" for s in st.slots
                                       if s.staged) +
                             "): plc-manager swap --publish, or --unstage")
        running = {s.type_name.upper(): s.build_id for s in st.slots}
        cands = swap_candidates(new, running)
        if not cands:
            progress(f"nothing to swap: every program type in {new} runs already")
            if restart:
                # the fixed build runs already (a swap without --restart
                # before): the restart alone is what is asked for
                proj = Project.open(Path(new).resolve())
                manifest = state.manifest if state is not None else proj.m
                _require_instances(manifest)
                rep.restarted = _restart_faulted(
                    c, manifest, [t["name"] for t in proj.m["program_types"]], progress)
            rep.total_ms = _ms(t_cmd, time.perf_counter())
            return rep
        loaded = kmod.loaded()
        # every check before anything is touched; interfaces first
        for cand in cands:
            _check_interface(cand, st, state)
        for cand in cands:
            _check_candidate(cand, st, loaded)
        manifest = None
        if restart:
            manifest = state.manifest if state is not None else cands[0].manifest
            _require_instances(manifest)
        rep.check_ms = _ms(t_cmd, time.perf_counter())
        steps = _prepare(c, cands, st, progress)
        rep.steps = steps
        rep.prepare_ms = _ms(t_cmd, time.perf_counter())
        if prepare_only:
            progress(f"prepared in {rep.prepare_ms:.1f} ms: publish with "
                     f"`plc-manager swap --publish`")
            rep.total_ms = rep.prepare_ms
            return rep
        _perform(c, steps, state, t_cmd, t_wall, progress,
                 {cand.type_name.upper(): str(cand.ko) for cand in cands}, rep=rep)
        rep.published = True
        if restart:
            rep.restarted = _restart_faulted(c, manifest, [x.type_name for x in cands],
                                             progress)
    rep.total_ms = _ms(t_cmd, time.perf_counter())
    return rep


def _restart_faulted(c: Client, manifest: dict, types: Sequence[str],
                     progress: Progress) -> List[str]:
    """Starts, one by one, the tasks stopped on a fault that run one of
    *types*; waits until each completed a cycle since.  A task that faults
    again fails the command, naming the fault."""
    using = set()
    for t in types:
        using.update(_tasks_running_type(manifest, t))
    st = c.status()
    faulted = [t for t in st.tasks() if t.state == "fault" and t.path.lower() in using]
    if not faulted:
        progress("no task running " + ", ".join(types) + " is stopped on a fault: nothing "
                 "to restart")
        return []
    before = {t.path: t.cycles for t in faulted}
    for t in faulted:
        progress(f"restarting task {t.path} (stopped on a fault: {fault_text(t)})")
        c.start(t.path)
    paths = set(before)

    def ran(s: Status) -> bool:
        return all(t.state == "running" and (t.cycles > before[t.path] or not t.interval_ns)
                   for t in s.tasks() if t.path in paths)
    timeout = 5.0 + 4 * max((t.interval_ns for t in faulted), default=0) / 1e9
    deadline = time.monotonic() + timeout
    while True:
        st = c.status()
        again = [t for t in st.tasks() if t.path in paths and t.state == "fault"]
        if again:
            t = again[0]
            raise PLCError(f"task {t.path} faulted again after the restart: {fault_text(t)}")
        if ran(st):
            break
        if time.monotonic() > deadline:
            raise PLCError(f"the restarted tasks ({', '.join(sorted(paths))}) completed no "
                           f"cycle within {timeout:.0f} s")
        time.sleep(0.005)
    for t in st.tasks():
        if t.path in paths:
            progress(f"  task {t.path} runs again ({t.cycles - before[t.path]} cycles since "
                     f"the restart, state kept)")
    return sorted(paths)
@contextlib.contextmanager
def _no_gc():
    """The cyclic garbage collector off for a short command whose latency
    counts (a full collection in a resident process costs tens of ms in a
    slow guest); it runs again after."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def publish(restart: bool = False, progress: Progress = _quiet) -> SwapReport:
    """The second half of a prepared swap (swap --prepare): publishes
    every staged build at once, confirms, removes the old modules;
    *restart* as for swap()."""
    with _no_gc():
        return _publish(restart, progress)


def _publish(restart: bool, progress: Progress) -> SwapReport:
    kmod.require(kmod.CAP_SYS_MODULE, "swap --publish")
    t_cmd = time.perf_counter()
    t_wall = time.time_ns()
    rep = SwapReport()
    with connect("swap --publish") as c:
        t = rep.mark("connect", t_cmd)
        st = c.status(slots_only=True)
        t = rep.mark("status", t)
        state = running_state(st)
        t = rep.mark("saved state", t)
        staged = [s for s in st.slots if s.staged]
        if not staged:
            raise UsageError("nothing is prepared: plc-manager swap --prepare NEW first")
        manifest = state.manifest if state is not None and restart else None
        if restart and not (manifest and "instances" in manifest):
            raise UsageError("swap --restart needs the manifest of the running configuration "
                             "(saved by plc-manager load) to know which tasks run the "
                             "swapped program types")
        loaded = kmod.loaded()
        for s in staged:
            mod = next((m for m in loaded if m.endswith(f"_{s.staged}") and
                        m != s.module), None)
            step = SwapStep(s.type_name, s.module, s.build_id, mod or "?", s.staged)
            step.staged = True
            rep.steps.append(step)
        rep.mark("modules", t)
        _perform(c, rep.steps, state, t_cmd, t_wall, progress, rep=rep)
        rep.published = True
        if restart:
            rep.restarted = _restart_faulted(c, manifest, [s.type_name for s in staged],
                                             progress)
    rep.total_ms = _ms(t_cmd, time.perf_counter())
    return rep


def unstage(progress: Progress = _quiet) -> None:
    """Drops a prepared swap: the staged builds leave their slots unpublished
    and their modules are removed."""
    kmod.require(kmod.CAP_SYS_MODULE, "swap --unstage")
    with connect("swap --unstage") as c:
        st = c.status()
        staged = [s for s in st.slots if s.staged]
        if not staged:
            progress("nothing is prepared")
            return
        loaded = kmod.loaded()
        c.unstage()
        for s in staged:
            for m in [m for m in loaded if m.endswith(f"_{s.staged}") and m != s.module]:
                kmod.remove(m)
                progress(f"unstaged {s.type_name}: removed {m}")


def _prepare(c: Client, cands: Sequence[Candidate], st: Status,
             progress: Progress) -> List[SwapStep]:
    """Inserts every candidate staged; on a failure removes what it staged."""
    steps: List[SwapStep] = []
    try:
        for cand in cands:
            slot = st.slot(cand.type_name)
            step = SwapStep(slot.type_name, slot.module, slot.build_id, cand.module,
                            cand.build_id, staged=True)
            t0 = time.perf_counter()
            kmod.insert(str(cand.ko), "stage=1")    # checked against its slot, staged there
            step.insert_ms = _ms(t0, time.perf_counter())
            steps.append(step)
        st = c.status()
        for step in steps:
            s = st.slot(step.type_name)
            if s is None or s.staged != step.new_build:
                raise PLCError(f"slot {step.type_name} has not staged {step.new_module} "
                               f"after inserting it")
    except BaseException:
        if steps:       # what this command staged goes (nothing else was staged)
            with contextlib.suppress(PLCError):
                c.unstage()
        for step in steps:
            with contextlib.suppress(PLCError):
                kmod.remove(step.new_module)
        raise
    for step in steps:
        progress(f"staged {step.type_name}: {step.new_module} ({step.insert_ms:.1f} ms)")
    return steps


def _record(state: State, step: SwapStep, ko: Optional[str]) -> None:
    """The saved state: *step*'s new build runs in its slot now."""
    state.record(step.type_name, step.new_module, step.new_build, ko)


def _perform(c: Client, steps: List[SwapStep], state: Optional[State], t_cmd: float,
             t_wall: int, progress: Progress, kos: Optional[Dict[str, str]] = None,
             rep: Optional[SwapReport] = None) -> None:
    """Publishes the staged builds (one command, every slot), then confirms
    each slot, waits for a cycle of each new body, removes the old modules."""
    kos = kos or {}
    rep = rep or SwapReport()
    t_perform = time.time_ns()
    t0 = time.perf_counter()
    _kernel_call(c, "publish", c.publish)     # pointer swaps, then one grace period
    t1 = time.perf_counter()
    st = c.status(slots_only=True)
    t2 = time.perf_counter()
    for step in steps:
        s2 = st.slot(step.type_name)
        if s2 is None or s2.build_id != step.new_build:
            raise PLCError(f"slot {step.type_name} does not run {step.new_module} after "
                           f"publishing it (it runs {s2.module if s2 else '?'})")
        step.new_module = s2.module or step.new_module
        step.insert_ms += _ms(t0, t1)
        step.confirm_ms = _ms(t1, t2)
        step.publish_ms = (s2.since_ns - t_wall) / 1e6
        step.perform_ms = (s2.since_ns - t_perform) / 1e6
        step.staged = False
    # wait for the first cycle of each new body: the kernel stamps it with
    # its time and its task (slots-only polls, a fraction of a status).  A
    # type that no running periodic task runs has none to wait for: the
    # full status, which says which tasks run, is asked for only if a
    # first cycle is not there within 10 ms.
    deadline = time.monotonic() + 5.0
    ask_tasks = time.monotonic() + 0.010
    pending = list(steps)
    told = False
    while True:
        for step in list(pending):
            s = st.slot(step.type_name)
            if s is not None and s.first_run_ns:
                step.first_cycle_ms = _ms(t2, time.perf_counter())
                step.first_cycle_task = s.first_run_task
                step.publication_to_first_ms = (s.first_run_ns - s.since_ns) / 1e6
                step.latency_ms = (s.first_run_ns - t_wall) / 1e6
                pending.remove(step)
        if not pending or time.monotonic() > deadline:
            break
        if not told and time.monotonic() > ask_tasks:
            told = True
            st = c.status()
            running = {t.path.lower() for t in st.tasks()
                       if t.state == "running" and t.interval_ns}
            manifest = state.manifest if state is not None else None
            pending = [step for step in pending
                       if running & set(_tasks_running_type(manifest, step.type_name))]
            continue
        time.sleep(0.001)
        st = c.status(slots_only=True)
    rep.phases["publish"] = _ms(t0, t1)
    rep.phases["confirm"] = _ms(t1, t2)
    t = rep.mark("first cycle", t2)
    for step in steps:
        if not step.latency_ms:
            step.latency_ms = _ms(t_cmd, time.perf_counter())
    for step in steps:
        if step.old_module:
            _remove_old(c, step)
        t = rep.mark("remove old", t)
        if state is not None:
            _record(state, step, kos.get(step.type_name.upper()))
        _report_step(step, progress)
        t = rep.mark("report", t)
    if state is not None:
        state.save()
        rep.mark("save state", t)


def _remove_old(c: Client, step: SwapStep) -> None:
    t4 = time.perf_counter()
    # the publication dropped the old module's reference after the grace
    # period: nothing can run the old body any more
    for _ in range(200):
        if kmod.refcnt(step.old_module) in (0, None):
            break
        time.sleep(0.005)
    try:
        kmod.remove(step.old_module)
    except PLCError as e:
        who = _stuck(c)
        raise PLCError(f"swapped {step.type_name} to build {step.new_build}, but the old "
                       f"module could not be removed: {e}" +
                       (f" ({who} does not come back: the old body may still run there)"
                        if who else "")) from None
    step.remove_ms = _ms(t4, time.perf_counter())


def _report_step(step: SwapStep, progress: Progress) -> None:
    progress(f"swapped {step.type_name}: {step.old_module or '(empty slot)'} -> "
             f"{step.new_module}")
    progress(f"  insert staged + publish {step.insert_ms:8.2f} ms   (relocation and checks, "
             f"then the RCU pointer swap and a grace period: no task runs the old body)")
    progress(f"  confirm slot       {step.confirm_ms:8.2f} ms   (slot runs build "
             f"{step.new_build})")
    if step.first_cycle_ms is not None:
        progress(f"  new body ran       {step.first_cycle_ms:8.2f} ms   "
                 f"(first cycle in task {step.first_cycle_task or '?'}, "
                 f"{step.publication_to_first_ms:.2f} ms after the publication)")
    else:
        progress("  new body ran            -      (no running periodic task uses it: "
                 "it runs at its next cycle)")
    if step.old_module:
        progress(f"  remove old module  {step.remove_ms:8.2f} ms   ({step.old_module})")
    progress(f"  command to publication {step.publish_ms:.2f} ms (publish command to "
             f"publication {step.perform_ms:.2f} ms), to new body running "
             f"{step.latency_ms:.2f} ms")


def _check_interface(cand: Candidate, st: Status, state: Optional[State]) -> None:
    slot = st.slot(cand.type_name)
    if cand.configuration and cand.configuration.lower() != st.configuration.lower():
        raise UsageError(f"swap refused: {cand.module} belongs to configuration "
                         f"{cand.configuration}, the running one is {st.configuration}")
    if slot is None:
        raise UsageError(f"swap refused: program type {cand.type_name} is not part of the "
                         f"running configuration {st.configuration}")
    if cand.interface_hash != slot.interface:
        old = None
        if state is not None:
            t = next((p for p in state.manifest["program_types"]
                      if p["name"].upper() == cand.type_name.upper()), None)
            old = t and t.get("interface")
        new = cand.entry and cand.entry.get("interface")
        changes = interface_changes(old, new) if old is not None and new is not None else []
        what = "; ".join(changes) if changes else \
            f"interface {slot.interface} -> {cand.interface_hash}" + \
            ("" if state is not None else " (the running configuration's manifest is unknown: "
             "no details)")
        raise UsageError(f"swap refused: the interface of program type {cand.type_name} "
                         f"changed ({what}); a hot swap changes algorithms, not interfaces: "
                         f"stop and load the configuration again")


def _check_candidate(cand: Candidate, st: Status, loaded: dict) -> None:
    slot = st.slot(cand.type_name)
    if slot.build_id == cand.build_id:
        raise UsageError(f"slot {slot.type_name} runs build {cand.build_id} already")
    if cand.module in loaded:
        raise UsageError(f"module {cand.module} is loaded already")
    if not cand.ko.is_file():
        raise UsageError(f"{cand.ko} is missing: the new build is not built "
                         f"(run `iec2kmod build`)")
    check_module_kernel(cand.ko)
    check_module_identity(cand.ko, cand.module, st.configuration,
                          cand.manifest.get("source_hash") if cand.manifest else None)


# ---------------------------------------------------------------------------
# variables

class Variables:
    """Variable names -> types, from the running configuration's manifest
    (saved at load, or --project), else from the kernel's variable table."""

    def __init__(self, c: Client, st: Status, project: Optional[str] = None) -> None:
        self.c = c
        self.st = st
        self.types: Dict[str, values.VarType] = {}
        self.aliases: Dict[str, str] = {}       # %IW2 -> path of its variable
        self.source = "kernel"
        manifest = None
        if project:
            p = Project.open(project)
            if p.configuration.lower() != st.configuration.lower():
                raise UsageError(f"{project} is configuration {p.configuration}, the running "
                                 f"one is {st.configuration}")
            manifest = p.m
            self.source = str(p.path)
        else:
            s = running_state(st)
            if s is not None:
                with contextlib.suppress(PLCError):     # its copy is gone: the kernel's table
                    manifest = s.manifest
                    self.source = "manifest"
        if manifest:
            # the manifest lists exactly the kernel's table, with the types
            for v in manifest["variables"]:
                self.types[v["path"].lower()] = values.VarType.from_manifest(v)
            # and the addresses of the located variables, names of them too
            for address, path in (manifest.get("addresses") or {}).items():
                if str(path).lower() in self.types:
                    self.aliases[str(address).lower()] = str(path).lower()
        else:
            for k in c.var_list():
                self.types[k.path.lower()] = values.VarType(path=k.path, kind=k.kind,
                                                            size=k.size, writable=k.writable)

    def get(self, name: str) -> values.VarType:
        key = name.strip().lower()
        t = self.types.get(self.aliases.get(key, key))
        if t is None:
            close = difflib.get_close_matches(name.lower(), list(self.types), n=3)
            names = [self.types[c].path for c in close]
            raise UsageError(f"unknown variable {name!r} in configuration "
                             f"{self.st.configuration}" +
                             (f" (did you mean {', '.join(names)}?)" if names else ""))
        return t

    def read(self, names: Sequence[str]) -> List[Tuple[values.VarType, VarValue, object]]:
        types = [self.get(n) for n in names]
        got = self.c.var_get([t.path for t in types])
        return [(t, v, values.decode(t, v.value)) for t, v in zip(types, got)]

    def parse(self, name: str, text: str, force: bool = False) -> Tuple[values.VarType, bytes]:
        t = self.get(name)
        if not force and not t.writable:
            raise UsageError(f"{t.path} is read-only")
        v = values.parse(t, text)
        return t, values.encode(t, v)

    def write(self, items: Sequence[Tuple[str, str]]) -> List[values.VarType]:
        enc = [self.parse(n, v) for n, v in items]
        try:
            self.c.var_set([(t.path, data) for t, data in enc])
        except KernelError as e:
            raise self._refused("write", e, [t for t, _ in enc]) from None
        return [t for t, _ in enc]

    def force(self, items: Sequence[Tuple[str, str]]) -> List[values.VarType]:
        enc = [self.parse(n, v, force=True) for n, v in items]
        try:
            self.c.var_force([(t.path, data) for t, data in enc])
        except KernelError as e:
            raise self._refused("force", e, [t for t, _ in enc]) from None
        return [t for t, _ in enc]

    def unforce(self, names: Sequence[str]) -> List[values.VarType]:
        types = [self.get(n) for n in names]
        try:
            self.c.var_unforce([t.path for t in types])
        except KernelError as e:
            raise self._refused("unforce", e, types) from None
        return types

    @staticmethod
    def _refused(what: str, e: KernelError, types) -> PLCError:
        name = types[0].path if len(types) == 1 else "a variable"
        if e.code == errno.EBUSY and what == "write":
            return UsageError(f"{name} is forced: unforce it first")
        if e.code == errno.ENODATA:
            return UsageError(f"{name} is not forced")
        if e.code == errno.EACCES:
            return UsageError(f"{name} is read-only")
        if e.code == errno.ENOENT:
            return UsageError(f"{name}: not in the kernel's variable table (the manifest does "
                              f"not match the running configuration?)")
        if e.code == errno.ENOSPC:
            return UsageError(f"too many forced variables (at most {MAX_FORCES}): unforce some")
        return PLCError(f"{what} refused by the kernel: {e}")
