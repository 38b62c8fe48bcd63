"""A small interpreter of the UPPAAL networks `iec2kmod export --uppaal`
writes, to replay simulator traces through the exported automata.

It reads the model with pyuppaal's parser (templates, locations, edges,
declarations, system) and runs it in discrete time: at each scan the Task
automaton leaves `wait` (its select values taken from the input trace),
follows its committed locations -- exactly one enabled edge each time, or
the model is wrong -- and synchronises with the timer automata on their
channels (sender's update first, then the receiver's, as UPPAAL does);
between scans every clock advances by the period."""

from __future__ import annotations

import re
import shutil
import tempfile
from pathlib import Path

TOKEN = re.compile(r"\s*(\d+|[A-Za-z_][A-Za-z0-9_]*|==|!=|<=|>=|&&|\|\||<<|>>|[-+*/%<>!~&|^?:(),=])")
BIN = [("?",), ("||",), ("&&",), ("|",), ("^",), ("&",), ("==", "!="), ("<", "<=", ">", ">="),
       ("<<", ">>"), ("+", "-"), ("*", "/", "%")]


def tokens(text):
    out = []
    pos = 0
    text = text.strip()
    while pos < len(text):
        m = TOKEN.match(text, pos)
        if not m:
            raise ValueError(f"cannot read {text[pos:]!r}")
        out.append(m.group(1))
        pos = m.end()
    return out


class Expr:
    """A C-like UPPAAL expression compiled to a Python function of an
    environment (a dict of variable values)."""

    def __init__(self, text):
        self.toks = tokens(text)
        self.i = 0
        src = self.ternary()
        if self.i != len(self.toks):
            raise ValueError(f"trailing {self.toks[self.i:]} in {text!r}")
        self.src = src
        self.fn = eval(f"lambda env: {src}", FUNCS)

    def peek(self):
        return self.toks[self.i] if self.i < len(self.toks) else None

    def take(self, t=None):
        tok = self.peek()
        if t is not None and tok != t:
            raise ValueError(f"expected {t}, found {tok}")
        self.i += 1
        return tok

    def ternary(self):
        c = self.binary(1)
        if self.peek() == "?":
            self.take()
            a = self.ternary()
            self.take(":")
            b = self.ternary()
            return f"(({a}) if ({c}) else ({b}))"
        return c

    def binary(self, level):
        if level >= len(BIN):
            return self.unary()
        left = self.binary(level + 1)
        while self.peek() in BIN[level]:
            op = self.take()
            right = self.binary(level + 1)
            if op == "&&":
                left = f"(bool({left}) and bool({right}))"
            elif op == "||":
                left = f"(bool({left}) or bool({right}))"
            elif op == "/":
                left = f"_div({left}, {right})"
            elif op == "%":
                left = f"_mod({left}, {right})"
            else:
                left = f"({left} {op} {right})"
        return left

    def unary(self):
        t = self.peek()
        if t == "!":
            self.take()
            return f"(not {self.unary()})"
        if t == "-":
            self.take()
            return f"(-{self.unary()})"
        if t == "~":
            self.take()
            return f"(~{self.unary()})"
        if t == "(":
            self.take()
            e = self.ternary()
            self.take(")")
            return e
        self.take()
        if t.isdigit():
            return t
        if t in ("true", "false"):
            return "True" if t == "true" else "False"
        if self.peek() == "(":
            self.take()
            args = []
            while self.peek() != ")":
                args.append(self.ternary())
                if self.peek() == ",":
                    self.take()
            self.take(")")
            return f"{t}({', '.join(args)})"
        return f"env[{t!r}]"


def _div(a, b):
    q = abs(a) // abs(b)
    return q if (a >= 0) == (b >= 0) else -q


def _mod(a, b):
    r = abs(a) % abs(b)
    return r if a >= 0 else -r


def _wrap(bits, signed):
    def w(v):
        v %= 1 << bits
        return v - (1 << bits) if signed and v >= 1 << (bits - 1) else v
    return w


FUNCS = {"_div": _div, "_mod": _mod, "wrap_s8": _wrap(8, True), "wrap_u8": _wrap(8, False),
         "wrap_s16": _wrap(16, True), "wrap_u16": _wrap(16, False), "bool": bool}


def split_top(text, sep=","):
    out, depth, cur = [], 0, ""
    for ch in text:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == sep and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    if cur.strip():
        out.append(cur)
    return [x.strip() for x in out]


def updates(text):
    if not text:
        return []
    out = []
    for part in split_top(text):
        name, expr = part.split("=", 1)
        out.append((name.strip(), Expr(expr)))
    return out


class Network:
    def __init__(self, path):
        from pyuppaal import UModel
        tmp = Path(tempfile.mkdtemp()) / "model.xml"
        shutil.copy(path, tmp)          # UModel writes the file back when it reads it
        self.model = UModel(str(tmp))
        self.env = {}
        self.types = {}
        for line in self.model.declaration.splitlines():
            line = line.split("//")[0].strip()
            m = re.match(r"(const\s+)?(bool|int(\[[-\d]+,[-\d]+\])?)\s+([A-Za-z_]\w*)\s*=\s*(.+);$",
                         line)
            if m:
                self.env[m.group(4)] = eval(m.group(5).replace("true", "True")
                                            .replace("false", "False"))
                self.types[m.group(4)] = m.group(2)
            m = re.match(r"clock\s+(\w+);", line)
            if m:
                self.env[m.group(1)] = 0
        self.templates = {t.name: t for t in self.model.templates}
        self.procs = {}     # process name -> (template, {param: global}, locals prefix)
        for line in self.model.system.splitlines():
            m = re.match(r"(\w+)\s*=\s*(\w+)\((.*)\);", line.strip())
            if m:
                t = self.templates[m.group(2)]
                params = [p.strip().split("&")[-1].strip() for p in t.params.split(",")]
                args = [a.strip() for a in m.group(3).split(",")]
                self.procs[m.group(1)] = (t, dict(zip(params, args)))
        self.task = self.templates["Task"]
        self.loc = {"Task": self.task.init_ref}
        self.chan = {}
        for name, (t, binding) in self.procs.items():
            self.loc[name] = t.init_ref
            self.chan[binding["call"]] = name
            prefix = name + "."
            for decl in (t.declaration or "").split(";"):
                decl = decl.strip()
                m = re.match(r"clock\s+(\w+)", decl)
                if m:
                    self.env[prefix + m.group(1)] = 0
                m = re.match(r"bool\s+(\w+)\s*=\s*(\w+)", decl)
                if m:
                    self.env[prefix + m.group(1)] = m.group(2) == "true"
        self.edges = {}
        for name, t in [("Task", self.task)] + [(n, p[0]) for n, p in self.procs.items()]:
            out = {}
            for e in t.edges:
                out.setdefault(e.source_location_id, []).append(
                    (e, Expr(e.guard) if e.guard else None, updates(e.update)))
            self.edges[name] = out
        self.committed = {lo.location_id for lo in self.task.locations if lo.is_committed}
        self.wait = next(lo.location_id for lo in self.task.locations if lo.name == "wait")
        self.period = self.env["PERIOD"]
        self.time = 0

    def view(self, proc):
        """The environment as a process sees it (its parameters and locals)."""
        if proc == "Task":
            return self.env
        t, binding = self.procs[proc]
        return _View(self.env, binding, proc + ".")

    def enabled(self, proc, sync_kind=None, chan=None):
        env = self.view(proc)
        out = []
        for e, g, ups in self.edges[proc].get(self.loc[proc], []):
            if sync_kind == "?" and (e.sync or "").strip() != "call?":
                continue
            if g is None or g.fn(env):
                out.append((e, ups))
        return out

    def apply(self, proc, ups, select=None):
        env = self.view(proc)
        if select:
            for k, v in select.items():
                env[k] = v
        for name, ex in ups:
            env[name] = ex.fn(env)

    def scan(self, inputs):
        """One scan with the input values {variable ident: value}."""
        # the scan edge: its select values are the trace's input values
        edges = self.enabled("Task")
        assert len(edges) == 1, f"{len(edges)} scan edges enabled at t={self.time}"
        e, ups = edges[0]
        select = {}
        for name, ex in ups:
            m = re.fullmatch(r"\(?\s*(i\d+)\s*(==\s*1)?\s*\)?", ex.src.replace("env['", "")
                             .replace("']", ""))
            if m and name in inputs:
                v = inputs[name]
                select[m.group(1)] = int(v) if not isinstance(v, bool) else (1 if v else 0)
        self.apply("Task", ups, select)
        self.loc["Task"] = e.target_location_id
        steps = 0
        while self.loc["Task"] in self.committed:
            steps += 1
            assert steps < 100000, "no way out of the committed locations"
            edges = self.enabled("Task")
            assert len(edges) == 1, \
                f"{len(edges)} edges enabled in committed location id{self.loc['Task']}"
            e, ups = edges[0]
            self.apply("Task", ups)
            sync = (e.sync or "").strip()
            if sync.endswith("!"):
                proc = self.chan[sync[:-1]]
                rec = self.enabled(proc, "?")
                assert len(rec) == 1, f"{len(rec)} receivers of {sync} in {proc}"
                re_, rups = rec[0]
                self.apply(proc, rups)
                self.loc[proc] = re_.target_location_id
            self.loc["Task"] = e.target_location_id
        assert self.loc["Task"] == self.wait
        # time passes to the next scan
        for k in list(self.env):
            if k == "c" or k.endswith(".x"):
                self.env[k] += self.period
        self.time += self.period


class _View(dict):
    def __init__(self, env, binding, prefix):
        super().__init__()
        self.env, self.binding, self.prefix = env, binding, prefix

    def _key(self, k):
        if k in self.binding:
            return self.binding[k]
        if self.prefix + k in self.env:
            return self.prefix + k
        return k

    def __getitem__(self, k):
        return self.env[self._key(k)]

    def __setitem__(self, k, v):
        self.env[self._key(k)] = v
