"""FBD and LD bodies (TC6 XML) -> ST statements (issue 28, slice 2).

A network is a graph of elements joined by connections (a connection names
the localId of the element whose output it reads, and for a block the
output pin, formalParameter).  The translation:

  * Values.  Every input point is an expression of what it is connected to:
    a variable (inVariable, inOutVariable), a function block instance's
    output (``inst.Q``), a function call (written in place, with its
    inputs in the block's pin order, when one element reads it; read by
    several, or with EN feeding a block, it is a statement of its own into
    a hidden variable of the output's type, inferred from its inputs, so
    that it is evaluated once), a connector read through its continuation,
    the left
    power rail (TRUE), a contact (``flow AND var``), a coil (its flow,
    passed through).  Several connections into one point are a wired OR
    (LD).  Negated pins and variables: NOT; an edge (rising/falling) on a
    contact, a block input or a variable: a hidden R_TRIG/F_TRIG instance
    called just before the statement that first needs it.
  * Statements: function block calls, outVariables, inOutVariables, coils,
    jumps and returns.  IEC 61131-3 (ed.2 4.1.3): an element is evaluated
    once all its inputs are; so the statements are topologically sorted by
    data flow (a statement reading an instance's output comes after that
    instance's call), ties broken by position (top to bottom, then left to
    right).  A feedback path (a cycle) is cut at the element that comes
    first in that order, which reads the value of the previous cycle.
    Where the editor gives an execution order (executionOrderId > 0, the
    TC6 attribute for it; 0 or absent: none), it is the order of the
    elements it numbers, data flow or not: an element that reads one
    numbered after it reads that one's value of the previous cycle, and a
    numbered function is evaluated at its place into a hidden variable
    (so it keeps that value); the elements left unnumbered follow the data
    flow around them.
  * Coils: ``v := flow`` (negated ``NOT flow``), set ``IF flow THEN v :=
    TRUE``, reset likewise FALSE, rising/falling: ``v := R_TRIG(flow).Q``.
  * EN of a function block instance: the call under ``IF en``; its ENO is
    EN.  EN of a function call is refused (its output without execution is
    not defined by the standard).
  * Labels cut the network into segments by their vertical position;
    statements after a jump run under a guard variable (``_JMP_``, the
    label's number while a jump is pending) until its label; return: ``IF
    cond THEN RETURN``.  A jump to a label above it (backward) makes the
    body a ``REPEAT ... UNTIL _JMP_ = 0`` loop: the pass after the jump
    skips the rest, the next one skips down to the label and resumes there
    (ed.2 4.1.3: control goes to the label), so a loop drawn with a jump
    runs under the execution model's loop budget like an ST loop.
"""

from __future__ import annotations

import heapq
import re

from .reader import XmlRefusal, _kid, _kids, _local

ELEMENTARY_NAMES = ("BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT",
                    "USINT", "UINT", "UDINT", "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT",
                    "TOD", "STRING", "WSTRING")
STD_FB_OUTPUTS = {("TON", "Q"): "BOOL", ("TON", "ET"): "TIME", ("TOF", "Q"): "BOOL",
                  ("TOF", "ET"): "TIME", ("TP", "Q"): "BOOL", ("TP", "ET"): "TIME",
                  ("CTU", "Q"): "BOOL", ("CTU", "CV"): "INT", ("CTD", "Q"): "BOOL",
                  ("CTD", "CV"): "INT", ("CTUD", "QU"): "BOOL", ("CTUD", "QD"): "BOOL",
                  ("CTUD", "CV"): "INT", ("R_TRIG", "Q"): "BOOL", ("F_TRIG", "Q"): "BOOL",
                  ("SR", "Q1"): "BOOL", ("RS", "Q1"): "BOOL",
                  ("RTC", "Q"): "BOOL", ("RTC", "CDT"): "DT"}
# the typed date and time functions (ed.2 table 30) by their result
DATE_ARITH = {"SUB_DT_DT": "TIME", "SUB_DATE_DATE": "TIME", "SUB_TOD_TOD": "TIME",
              "ADD_DT_TIME": "DT", "SUB_DT_TIME": "DT", "ADD_TOD_TIME": "TOD",
              "SUB_TOD_TIME": "TOD", "CONCAT_DATE_TOD": "DT"}
STATEMENTS = ("block", "outVariable", "inOutVariable", "coil", "jump", "return")
KNOWN = STATEMENTS + ("inVariable", "connector", "continuation", "label", "comment",
                      "leftPowerRail", "rightPowerRail", "contact", "addData",
                      "documentation", "actionBlock", "vendorElement")
# the FBD/LD elements an SFC body may hold beside its chart (Beremiz)
GRAPHIC = ("block", "inVariable", "outVariable", "inOutVariable", "contact", "coil",
           "leftPowerRail", "rightPowerRail", "connector", "continuation")
SFC_KINDS = ("step", "transition", "selectionDivergence", "selectionConvergence",
             "simultaneousDivergence", "simultaneousConvergence", "jumpStep", "actionBlock",
             "comment", "addData", "documentation")


def _text(el, name):
    k = _kid(el, name)
    return "".join(k.itertext()).strip() if k is not None else ""


def _pos(el):
    p = _kid(el, "position")
    try:
        return (float(p.get("y")), float(p.get("x"))) if p is not None else (0.0, 0.0)
    except (TypeError, ValueError):
        return (0.0, 0.0)


# the marks of the parts of a generated line that other elements wrote:
# MARK_OPEN index MARK_SEP text MARK_CLOSE (reader's emit() takes them out)
MARK_OPEN, MARK_SEP, MARK_CLOSE = "\x01", "\x02", "\x03"
_MARKS = re.compile("\x01[0-9]+\x02|\x03")


def plain(text):
    """text without its marks."""
    return _MARKS.sub("", text)


def spans(text):
    """(text without its marks, [(first column, last column, mark index)])
    with 1-based columns of the unmarked text."""
    out, stack, found = [], [], []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == MARK_OPEN:
            j = text.index(MARK_SEP, i)
            stack.append((int(text[i + 1:j]), len(out)))
            i = j + 1
            continue
        if c == MARK_CLOSE:
            idx, start = stack.pop()
            found.append((start + 1, len(out), idx))
        else:
            out.append(c)
        i += 1
    return "".join(out), found


def _true(v):
    return v in ("true", "1")


class Network:
    def __init__(self, gen, body, ctx, pou_kind, user_functions, sfc=False):
        self.gen = gen                   # the reader's _Generator (emit)
        self.body = body
        self.ctx = ctx
        self.kind = pou_kind
        self.user = user_functions       # names of the project's functions
        self.els = {}
        self.connectors = {}
        self.hidden = []                 # (name, type) to declare in the POU
        self.pre = []                    # statements a value needs first
        self.done_trig = {}              # key -> trig instance name
        self.implied = set()             # blocks with EN known to run (enabled_value)
        self.temps = {}                  # localId -> variable holding a function's output
        self.backward = False            # a jump to a label above it (order() tells)
        self.unconnected = set()         # outVariables/coils with no input (warned)
        for e in _kids(body):
            k = _local(e)
            if sfc and k in SFC_KINDS:
                lid = e.get("localId")
                if lid is not None:
                    self.els[lid] = e
                continue
            if k not in (GRAPHIC if sfc else KNOWN):
                raise XmlRefusal(e, f"element <{k}> (localId {e.get('localId')}) in the "
                                    f"{_local(body)} body of {ctx} is not supported")
            lid = e.get("localId")
            if lid is not None:
                self.els[lid] = e
            if k == "connector":
                self.connectors[e.get("name")] = e
            if k == "actionBlock":
                raise XmlRefusal(e, f"<actionBlock> (localId {lid}) outside an SFC body of {ctx}")
            if k == "vendorElement":
                raise XmlRefusal(e, f"<vendorElement> (localId {lid}) in {ctx}: vendor elements "
                                    f"are not supported")
        self.plan_temps()

    # -- naming
    def label(self, e):
        k = _local(e)
        name = (e.get("instanceName") or e.get("typeName") if k == "block" else
                _text(e, "expression") or _text(e, "variable") or e.get("label") or e.get("name")
                or k)
        return f"block localId {e.get('localId')} '{name}'"

    def trig(self, kind, expr, e, key):
        """The Q of a hidden R_TRIG/F_TRIG instance fed with expr, called
        before the current statement (once per key)."""
        if self.kind == "function":
            raise XmlRefusal(e, f"edge detection in {self.label(e)} of {self.ctx}: a function "
                                f"has no memory (use a function block)")
        name = self.done_trig.get(key)
        if name is None:
            fb = "R_TRIG" if kind == "rising" else "F_TRIG"
            name = f"_{fb}_{e.get('localId')}_{len(self.done_trig)}"
            self.hidden.append((name, fb))
            self.done_trig[key] = name
            self.pre.append((f"{name}(CLK := {expr});", e))
        return f"{name}.Q"

    def mark(self, el, text, label=None):
        """text, marked as written for el (spans(): a diagnostic whose
        column falls in it points at el's line and names it)."""
        return self.gen.mark(el, label or self.label(el), text)

    # -- values
    def point(self, cpin, e, what):
        if cpin is None:
            raise XmlRefusal(e, f"{what} of {self.label(e)} in {self.ctx} is not connected")
        conns = _kids(cpin, "connection")
        expr = _kid(cpin, "expression")
        if not conns and expr is not None and (expr.text or "").strip():
            return f"({expr.text.strip()})"
        if not conns:
            raise XmlRefusal(cpin, f"{what} of {self.label(e)} in {self.ctx} is not connected")
        vals = [self.output(c, e) for c in conns]
        return vals[0] if len(vals) == 1 else "(" + " OR ".join(vals) + ")"

    def output(self, conn, user):
        ref = conn.get("refLocalId")
        src = self.els.get(ref)
        if src is None:
            raise XmlRefusal(conn, f"connection of {self.label(user)} in {self.ctx} to localId "
                                   f"{ref}, which is not in the body")
        k = _local(src)
        pin = conn.get("formalParameter") or ""
        if k in ("inVariable", "inOutVariable"):
            v = _text(src, "expression")
            if not v:
                raise XmlRefusal(src, f"{self.label(src)} in {self.ctx} has no <expression>")
            v = f"({v})" if not v.replace("_", "").replace(".", "").isalnum() else v
            v = self.mark(src, v)
            if src.get("edge") in ("rising", "falling"):
                v = self.trig(src.get("edge"), v, src, ("v", ref))
            return f"NOT {v}" if _true(src.get("negated")) else v
        if k == "leftPowerRail":
            return "TRUE"
        if k == "continuation":
            c = self.connectors.get(src.get("name"))
            if c is None:
                raise XmlRefusal(src, f"continuation '{src.get('name')}' (localId {ref}) in "
                                      f"{self.ctx} has no connector of that name")
            return self.point(_kid(c, "connectionPointIn"), c, "the input")
        if k == "contact":
            flow = self.point(_kid(src, "connectionPointIn"), src, "the left link")
            var = _text(src, "variable")
            term = self.mark(src, var)
            if src.get("edge") in ("rising", "falling"):
                term = self.trig(src.get("edge"), var, src, ("c", ref))
            if _true(src.get("negated")):
                term = f"NOT {term}"
            return term if flow == "TRUE" else f"({flow} AND {term})"
        if k == "coil":
            return self.point(_kid(src, "connectionPointIn"), src, "the left link")
        if k == "block":
            return self.block_output(src, pin, conn)
        raise XmlRefusal(conn, f"connection of {self.label(user)} in {self.ctx} to <{k}> "
                               f"(localId {ref}), which has no output")

    def pins(self, blk, section):
        sec = _kid(blk, section)
        return _kids(sec, "variable") if sec is not None else []

    def pin_value(self, blk, v):
        cpin = _kid(v, "connectionPointIn")
        if cpin is None or not _kids(cpin, "connection"):
            return None
        val = self.point(cpin, blk, f"input {v.get('formalParameter')}")
        if v.get("edge") in ("rising", "falling"):
            val = self.trig(v.get("edge"), val, blk, ("p", blk.get("localId"),
                                                       v.get("formalParameter")))
        if _true(v.get("negated")):
            val = f"NOT {val}" if val.replace("_", "").replace(".", "").isalnum() \
                else f"NOT ({val})"
        return val

    def en(self, blk):
        for v in self.pins(blk, "inputVariables"):
            if v.get("formalParameter") == "EN":
                val = self.pin_value(blk, v)
                # not connected, or on the power rail: always enabled
                return None if val is None or plain(val) == "TRUE" else val
        return None

    def block_output(self, blk, pin, conn):
        inst = blk.get("instanceName")
        outs = {v.get("formalParameter"): v for v in self.pins(blk, "outputVariables")}
        outs.update({v.get("formalParameter"): v for v in self.pins(blk, "inOutVariables")})
        if not pin:
            real = [p for p in outs if p != "ENO"]
            if len(real) != 1:
                raise XmlRefusal(conn, f"connection to {self.label(blk)} in {self.ctx} does not "
                                       f"name the output pin")
            pin = real[0]
        v = outs.get(pin)
        if v is None and pin != "ENO":
            raise XmlRefusal(conn, f"{self.label(blk)} in {self.ctx} has no output '{pin}'")
        neg = v is not None and _true(v.get("negated"))
        if pin == "ENO":
            val = self.en(blk) or "TRUE"
        elif inst:
            val = self.mark(blk, f"{inst}.{pin}")
        elif blk.get("localId") in self.temps:
            val = self.temps[blk.get("localId")]
        else:
            val = self.mark(blk, self.call(blk, pin))
        return f"NOT {val}" if neg else val

    # -- functions evaluated once
    def plan_temps(self):
        """A function whose output several elements read, or whose EN is
        connected and whose output feeds a block, is evaluated once, as a
        statement in the data-flow order, into a variable of its output
        type (IEC 61131-3 4.1.3: each element is evaluated once); the
        others are written where their one reader needs them."""
        readers = {}
        direct = {}
        for c in self.body.iter():
            if not isinstance(c.tag, str) or _local(c) != "connection":
                continue
            src = self.els.get(c.get("refLocalId"))
            if src is None or _local(src) != "block" or src.get("instanceName") or \
                    (c.get("formalParameter") or "OUT") == "ENO":
                continue
            lid = src.get("localId")
            readers[lid] = readers.get(lid, 0) + 1
            owner = c.getparent().getparent() if c.getparent() is not None else None
            direct[lid] = owner is not None and _local(owner) in ("outVariable", "coil",
                                                                  "inOutVariable")
        for lid, n in readers.items():
            blk = self.els[lid]
            en = any(v.get("formalParameter") == "EN" and
                     _kids(_kid(v, "connectionPointIn"), "connection")
                     for v in self.pins(blk, "inputVariables")
                     if _kid(v, "connectionPointIn") is not None)
            # a function the editor numbered runs at its place in that order
            # (its readers numbered before it read its previous value)
            if n < 2 and not (en and not direct[lid]) and not self.order_id(blk):
                continue
            typ = self.infer(blk, set()) or self.infer_from_readers(blk)
            if typ is None:
                if n >= 2:
                    raise XmlRefusal(blk, f"the output of {self.label(blk)} in {self.ctx} is "
                                          f"read {n} times and its type cannot be told from its "
                                          f"inputs (give one input a typed literal or a "
                                          f"variable)")
                continue          # call() refuses the EN case by name
            name = f"_TMP_{blk.get('typeName')}{lid}_OUT"
            self.temps[lid] = name
            self.hidden.append((name, typ))

    def infer(self, blk, seen):
        """The type of a function block's output, or None."""
        name = (blk.get("typeName") or "").upper()
        if blk.get("localId") in seen:
            return None
        seen = seen | {blk.get("localId")}
        if name in ("GT", "GE", "EQ", "LE", "LT", "NE"):
            return "BOOL"
        m = re.match(r"^(?:[A-Z]+_)?TO_([A-Z]+)$|^[A-Z]+_TO_([A-Z]+)$", name)
        if m and (m.group(1) or m.group(2)) in ELEMENTARY_NAMES:
            return m.group(1) or m.group(2)
        if name in self.gen.fn_returns:
            return self.gen.fn_returns[name]
        if name in DATE_ARITH:
            return DATE_ARITH[name]
        if name == "SUB":
            # the difference of two dates or times of day is a duration
            ins = []
            for v in self.pins(blk, "inputVariables"):
                if v.get("formalParameter") in ("IN1", "IN2"):
                    cpin = _kid(v, "connectionPointIn")
                    cs = _kids(cpin, "connection") if cpin is not None else []
                    ins.append(self.infer_conn(cs[0], seen) if cs else None)
            if len(ins) == 2 and ins[0] == ins[1] and ins[0] in ("DT", "DATE", "TOD"):
                return "TIME"
        skip = {"SEL": ("G",), "MUX": ("K",), "LIMIT": (), "SHL": ("N",), "SHR": ("N",),
                "ROL": ("N",), "ROR": ("N",)}.get(name, ())
        if name in ("LEN", "FIND"):
            return "INT"
        for v in self.pins(blk, "inputVariables"):
            if v.get("formalParameter") in ("EN",) + skip:
                continue
            cpin = _kid(v, "connectionPointIn")
            for c in _kids(cpin, "connection") if cpin is not None else []:
                t = self.infer_conn(c, seen)
                if t is not None:
                    return t
        return None

    def infer_from_readers(self, blk):
        """The type of a function's output from what reads it, when its own
        inputs do not tell (literals only): a variable it is stored into,
        or the other inputs of a function it feeds."""
        lid = blk.get("localId")
        for c in self.body.iter():
            if not isinstance(c.tag, str) or _local(c) != "connection" or \
                    c.get("refLocalId") != lid:
                continue
            cpin = c.getparent()
            owner = cpin.getparent() if cpin is not None else None
            if owner is None:
                continue
            if _local(owner) in ("outVariable", "inOutVariable"):
                t = self.var_type(_text(owner, "expression"))
                if t is not None:
                    return t
            if _local(owner) == "variable":          # a pin of a block
                reader = owner.getparent().getparent()
                if reader is None or _local(reader) != "block" or reader.get("instanceName"):
                    continue
                if (reader.get("typeName") or "").upper() in ("SEL", "MUX") and \
                        owner.get("formalParameter") in ("G", "K"):
                    continue
                if (reader.get("typeName") or "").upper() not in (
                        "ADD", "SUB", "MUL", "DIV", "MOD", "MAX", "MIN", "SEL", "MUX", "LIMIT",
                        "GT", "GE", "EQ", "LE", "LT", "NE", "AND", "OR", "XOR", "MOVE"):
                    continue
                for v in self.pins(reader, "inputVariables"):
                    if v is owner or v.get("formalParameter") in ("EN", "G", "K"):
                        continue
                    vin = _kid(v, "connectionPointIn")
                    for c2 in _kids(vin, "connection") if vin is not None else []:
                        if c2.get("refLocalId") != lid:
                            t = self.infer_conn(c2, {lid})
                            if t is not None:
                                return t
        return None

    def infer_conn(self, c, seen):
        src = self.els.get(c.get("refLocalId"))
        if src is None:
            return None
        k = _local(src)
        if k in ("contact", "coil", "leftPowerRail"):
            return "BOOL"
        if k == "continuation":
            con = self.connectors.get(src.get("name"))
            cpin = _kid(con, "connectionPointIn") if con is not None else None
            cs = _kids(cpin, "connection") if cpin is not None else []
            return self.infer_conn(cs[0], seen) if cs else None
        if k in ("inVariable", "inOutVariable"):
            return self.var_type(_text(src, "expression"))
        if k == "block":
            pin = (c.get("formalParameter") or "").upper()
            if pin == "ENO":
                return "BOOL"
            inst = src.get("instanceName")
            if inst:
                fb = (self.gen.var_types.get(inst.upper()) or "").upper()
                return STD_FB_OUTPUTS.get((fb, pin)) or \
                    self.gen.fb_outputs.get(fb, {}).get(pin)
            return self.infer(src, seen)
        return None

    def var_type(self, expr):
        e = expr.strip()
        u = e.upper()
        if u in ("TRUE", "FALSE"):
            return "BOOL"
        m = re.match(r"^([A-Z]+)#", u)
        if m:
            kind = {"T": "TIME", "TIME": "TIME", "D": "DATE", "DATE": "DATE", "TOD": "TOD",
                    "TIME_OF_DAY": "TOD", "DT": "DT", "DATE_AND_TIME": "DT"}.get(m.group(1))
            if kind:
                return kind
            if m.group(1) in ELEMENTARY_NAMES:
                return m.group(1)
            return None
        if e.startswith("'"):
            return "STRING"
        parts = u.split(".")
        if not all(re.match(r"^[A-Z_][A-Z0-9_]*$", p) for p in parts):
            return None
        t = self.gen.var_types.get(parts[0])
        if t is None or len(parts) == 1:
            return t if t is None or t.upper() in ELEMENTARY_NAMES or \
                t.upper().startswith(("STRING", "WSTRING")) else t
        if len(parts) == 2:
            fb = t.upper()
            return STD_FB_OUTPUTS.get((fb, parts[1])) or \
                self.gen.fb_outputs.get(fb, {}).get(parts[1])
        return None

    def refuse_fn_en(self, blk):
        raise XmlRefusal(blk, f"EN of the function call {self.label(blk)} in {self.ctx} is "
                              f"connected and its output feeds another block: only a variable "
                              f"or a coil may take the output of a function with EN (it is "
                              f"stored when EN is TRUE)")

    def call(self, blk, pin, guarded=False):
        name = blk.get("typeName")
        if not guarded and blk.get("localId") not in self.implied and \
                self.en(blk) is not None:
            self.refuse_fn_en(blk)
        outs = [v.get("formalParameter") for v in self.pins(blk, "outputVariables")
                if v.get("formalParameter") != "ENO"]
        if outs != ["OUT"] or pin != "OUT" or self.pins(blk, "inOutVariables"):
            raise XmlRefusal(blk, f"function call {self.label(blk)} in {self.ctx}: only "
                                  f"functions with one output OUT are supported")
        args = []
        for v in self.pins(blk, "inputVariables"):
            p = v.get("formalParameter")
            if p == "EN":
                continue
            val = self.pin_value(blk, v)
            if val is None:
                if name.upper() in self.user:
                    continue
                raise XmlRefusal(v, f"input {p} of {self.label(blk)} in {self.ctx} is not "
                                    f"connected")
            args.append(self.mark(blk, f"{p} := {val}" if name.upper() in self.user else val,
                                  f"input {p} of {self.label(blk)}"))
        return f"{name}({', '.join(args)})"

    # -- statements
    def statement(self, e):
        """(lines, element) of one statement element."""
        k = _local(e)
        self.pre = []
        self.implied = set()
        lines = []
        if k == "block" and not e.get("instanceName"):
            tmp = self.temps.get(e.get("localId"))
            if tmp is None:
                return []             # a function: evaluated where its output is read
            en = self.en(e)
            line = f"{tmp} := {self.call(e, 'OUT', guarded=True)};"
            lines = [line] if en is None else [f"IF {en} THEN", f"    {line}", "END_IF;"]
        elif k == "block":
            inst = e.get("instanceName")
            args = []
            for sec in ("inputVariables", "inOutVariables"):
                for v in self.pins(e, sec):
                    p = v.get("formalParameter")
                    if p == "EN":
                        continue
                    val = self.pin_value(e, v)
                    if val is not None:
                        args.append(self.mark(e, f"{p} := {val}",
                                              f"input {p} of {self.label(e)}"))
            en = self.en(e)
            call = f"{inst}({', '.join(args)});"
            lines = [call] if en is None else [f"IF {en} THEN", f"    {call}", "END_IF;"]
        elif k in ("outVariable", "inOutVariable", "coil"):
            target = _text(e, "expression" if k != "coil" else "variable")
            cpin = _kid(e, "connectionPointIn")
            if cpin is None or not (_kids(cpin, "connection") or
                                    (_text(cpin, "expression") if k != "coil" else "")):
                # nothing drawn into it: it stores nothing (Beremiz's
                # generator skips it too); said, since it is likely a
                # drawing left unfinished
                if e.get("localId") not in self.unconnected:
                    self.unconnected.add(e.get("localId"))
                    from .reader import _diag
                    _diag(self.gen.tr, e.sourceline or 1, "warning",
                          f"{self.label(e)} in {self.ctx} is not connected: ignored (it "
                          f"stores nothing)")
                return []
            en, val = self.enabled_value(cpin, e)
            if val is None:
                val = self.point(cpin, e, "the input" if k != "coil" else "the left link")
            if _true(e.get("negated")):
                val = f"NOT ({val})" if plain(val) != "TRUE" else "FALSE"
            lines = self.store(e, target, val)
            if en is not None:
                # IEC 61131-3 ed.2 2.5.1.2: with EN FALSE the block is not
                # executed, so nothing it computes is stored (Beremiz: the
                # value passes when ENO is TRUE)
                lines = [f"IF {en} THEN"] + ["    " + x for x in lines] + ["END_IF;"]
        elif k == "jump":
            cond = self.point(_kid(e, "connectionPointIn"), e, "the condition")
            lines = [f"IF {cond} THEN", f"    _JMP_ := {self.label_index[e.get('label')]};",
                     "END_IF;"]
        elif k == "return":
            cond = self.point(_kid(e, "connectionPointIn"), e, "the condition")
            lines = [f"IF {cond} THEN", "    RETURN;", "END_IF;"]
        out = [(s, el) for s, el in self.pre] + [(s, e) for s in lines]
        self.pre = []
        return out

    def enabled_value(self, cpin, e):
        """(EN, value) when cpin reads one output (not ENO) of a block whose
        EN is connected, else (None, None)."""
        conns = _kids(cpin, "connection") if cpin is not None else []
        if len(conns) != 1:
            return None, None
        src = self.els.get(conns[0].get("refLocalId"))
        pin = conns[0].get("formalParameter") or ""
        if src is None or _local(src) != "block" or pin == "ENO":
            return None, None
        en = self.en(src)
        if en is None:
            return None, None
        # the blocks that surely ran when this one did: those whose ENO is
        # its EN, and so on up the chain (a chain of MOVEs, SUB -> LT -> SEL)
        b = src
        while b is not None and b.get("localId") not in self.implied:
            self.implied.add(b.get("localId"))
            env = next((v for v in self.pins(b, "inputVariables")
                        if v.get("formalParameter") == "EN"), None)
            cs = _kids(_kid(env, "connectionPointIn"), "connection") \
                if env is not None and _kid(env, "connectionPointIn") is not None else []
            b = None
            if len(cs) == 1 and cs[0].get("formalParameter") == "ENO":
                b = self.els.get(cs[0].get("refLocalId"))
                if b is not None and _local(b) != "block":
                    b = None
        if src.get("instanceName"):
            return en, self.block_output(src, pin, conns[0])
        outs = [v.get("formalParameter") for v in self.pins(src, "outputVariables")
                if v.get("formalParameter") != "ENO"]
        val = self.temps.get(src.get("localId")) or \
            self.call(src, pin or (outs[0] if len(outs) == 1 else ""), guarded=True)
        v = next((v for v in self.pins(src, "outputVariables")
                  if v.get("formalParameter") == (pin or "OUT")), None)
        if v is not None and _true(v.get("negated")):
            val = f"NOT {val}"
        return en, val

    def store(self, e, target, val):
        if not target:
            raise XmlRefusal(e, f"{self.label(e)} in {self.ctx} names no variable")
        st = e.get("storage")
        edge = e.get("edge")
        if edge in ("rising", "falling"):
            val = self.trig(edge, val, e, ("s", e.get("localId")))
            if st in ("set", "reset"):
                raise XmlRefusal(e, f"{self.label(e)} in {self.ctx}: an edge and a storage "
                                    f"together")
        if st == "set":
            return [f"IF {val} THEN", f"    {target} := TRUE;", "END_IF;"]
        if st == "reset":
            return [f"IF {val} THEN", f"    {target} := FALSE;", "END_IF;"]
        return [f"{target} := {val};"]

    # -- order
    def deps(self, e):
        """The statement elements whose results e reads (transitively
        through functions, contacts, coils' flow and continuations)."""
        out = set()
        seen = set()

        def walk(el):
            for cpin in _kids(el, "connectionPointIn"):
                for c in _kids(cpin, "connection"):
                    src = self.els.get(c.get("refLocalId"))
                    if src is None or id(src) in seen:
                        continue
                    seen.add(id(src))
                    k = _local(src)
                    if k == "block" and (src.get("instanceName") or
                                         src.get("localId") in self.temps):
                        out.add(src.get("localId"))
                    elif k == "inOutVariable":
                        out.add(src.get("localId"))
                    elif k == "continuation":
                        con = self.connectors.get(src.get("name"))
                        if con is not None:
                            walk(con)
                    else:
                        walk(src)
            for sec in ("inputVariables", "inOutVariables"):
                for v in self.pins(el, sec) if _local(el) == "block" else []:
                    walk(v)
        walk(e)
        out.discard(e.get("localId"))
        return out

    def order(self):
        stmts = [e for e in _kids(self.body) if _local(e) in STATEMENTS and
                 (_local(e) != "block" or e.get("instanceName") or
                  e.get("localId") in self.temps)]
        labels = sorted((e for e in _kids(self.body) if _local(e) == "label"), key=_pos)
        self.backward = False
        self.label_index = {}
        for i, lab in enumerate(labels):
            self.label_index[lab.get("label")] = i + 1

        def segment(e):
            y = _pos(e)[0]
            return sum(1 for lab in labels if _pos(lab)[0] <= y)
        for j in (e for e in stmts if _local(e) == "jump"):
            target = self.label_index.get(j.get("label"))
            if target is None:
                raise XmlRefusal(j, f"{self.label(j)} in {self.ctx}: no label "
                                    f"'{j.get('label')}' in the body")
            if target <= segment(j):
                self.backward = True
        num = {e.get("localId"): self.order_id(e) for e in stmts}

        def key(e):
            return (segment(e), num[e.get("localId")], _pos(e), int(e.get("localId") or 0))
        by_id = {e.get("localId"): e for e in stmts}
        deps = {e.get("localId"): {d for d in self.deps(e) if d in by_id
                                   and segment(by_id[d]) == segment(e)} for e in stmts}
        # the editor's order (executionOrderId > 0) is the execution order of
        # the elements it numbers: between two numbered elements it replaces
        # the data flow (one that reads an element numbered after it reads
        # that element's value of the previous cycle); the elements it does
        # not number follow the data flow around them.  Labels still cut
        # the body into segments (jumps), so only within a segment.
        numbered = [lid for lid, n in num.items() if n > 0]
        for lid in numbered:
            seg = segment(by_id[lid])
            deps[lid] = {d for d in deps[lid] if num[d] == 0 or num[d] == num[lid]} | \
                {d for d in numbered if 0 < num[d] < num[lid] and segment(by_id[d]) == seg}
        ordered = []
        left = {e.get("localId"): e for e in stmts}
        while left:
            ready = [e for lid, e in left.items() if not (deps[lid] & left.keys())]
            if not ready:
                # a feedback path: the first element of a cycle in position
                # order goes first and reads the previous cycle's values
                ready = [e for lid, e in left.items() if self.on_cycle(lid, deps, left)]
            heap = [(key(e), i, e) for i, e in enumerate(ready)]
            heapq.heapify(heap)
            e = heap[0][2]
            ordered.append(e)
            del left[e.get("localId")]
        return ordered, labels, segment

    def order_id(self, e):
        """The executionOrderId the editor gave e (0: none)."""
        v = e.get("executionOrderId")
        if v is None:
            return 0
        try:
            n = int(v)
        except ValueError:
            n = -1
        if n < 0:
            raise XmlRefusal(e, f"{self.label(e)} in {self.ctx}: executionOrderId '{v}' is not "
                                f"a non-negative integer")
        return n

    @staticmethod
    def on_cycle(lid, deps, left):
        seen, stack = set(), [d for d in deps[lid] if d in left]
        while stack:
            d = stack.pop()
            if d == lid:
                return True
            if d not in seen:
                seen.add(d)
                stack += [x for x in deps[d] if x in left]
        return False

    def translate(self):
        """[(line, element, ctx)] of the body's ST, and the hidden variables."""
        ordered, labels, segment = self.order()
        jumps = any(_local(e) == "jump" for e in ordered)
        out = []
        if jumps:
            self.hidden.append(("_JMP_", "INT"))
            out.append(("_JMP_ := 0;", self.body, None))
        seg = 0
        for e in ordered:
            s = segment(e)
            while jumps and seg < s:
                seg += 1
                lab = labels[seg - 1]
                out.append((f"IF _JMP_ = {seg} THEN _JMP_ := 0; END_IF;", lab, self.label(lab)))
            lines = self.statement(e)
            if jumps and lines:
                out.append(("IF _JMP_ = 0 THEN", e, self.label(e)))
                out += [("    " + s_, el, self.label(el)) for s_, el in lines]
                out.append(("END_IF;", e, self.label(e)))
            else:
                out += [(s_, el, self.label(el)) for s_, el in lines]
        if self.backward:
            # a jump to a label above it: the body is the pass of a loop
            # that runs again from the top while a jump is pending (the
            # statements are skipped down to the label), so it runs under
            # the task's loop budget like any ST loop
            body = [("    " + s_, el, c) for s_, el, c in out[1:]]
            out = [out[0], ("REPEAT", self.body, None)] + body + \
                [("UNTIL _JMP_ = 0", self.body, None), ("END_REPEAT;", self.body, None)]
        return out
