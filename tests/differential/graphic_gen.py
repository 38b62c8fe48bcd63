"""Random LD and FBD networks as PLCopen XML, each with a referee: the same
program written directly in ST by this generator from the standard's rules
(issue 28).  The XML goes through iec2kmod/plcopen (the translation under
test); the ST does not.  Both run in the engines on the same random inputs
and every output must have the same value after every cycle.

``generate(seed)`` -> GraphicProject(xml, st, inputs, outputs, cycles): one
PROGRAM ``prog`` (instance ``inst`` of resource ``res``, task every 10 ms)
whose body is LD rungs or an FBD network.  What the referee encodes:

  * LD (IEC 61131-3 ed.2 4.2): rungs evaluated top to bottom; a contact
    passes its left link AND its variable (negated: AND NOT; rising/falling:
    AND an R_TRIG/F_TRIG of the variable, called before the rung's coil);
    parallel branches join by OR; coils: normal, negated, set (S), reset
    (R), rising (P) and falling (N) coils.
  * FBD (4.3): functions (AND, OR, XOR, NOT, ADD, SUB, MAX, MIN, SEL, GT,
    EQ, LE, AND of negated pins) and function blocks (CTU, TON, R_TRIG, SR)
    connected as a DAG, every element evaluated once, before the elements
    that read it; an output read by several elements is the same value;
    elements are drawn at random positions, so drawing order is not data
    order; the outVariables are sinks (nothing in the network reads them).
    In some networks every block and outVariable carries the editor's
    execution order (executionOrderId, a random permutation): the referee
    runs them in that order, each function into a variable of its own, so
    an element read before it runs gives its value of the previous cycle.

Deterministic for a seed (random.Random(seed) only).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

HEADER = """<?xml version='1.0' encoding='utf-8'?>
<project xmlns="http://www.plcopen.org/xml/tc6_0201" xmlns:xhtml="http://www.w3.org/1999/xhtml">
  <fileHeader companyName="iec2kmod" productName="graphic_gen" productVersion="1" creationDateTime="2026-11-27T07:00:00"/>
  <contentHeader name="graphic_gen">
    <coordinateInfo>
      <fbd><scaling x="0" y="0"/></fbd>
      <ld><scaling x="0" y="0"/></ld>
      <sfc><scaling x="0" y="0"/></sfc>
    </coordinateInfo>
  </contentHeader>
  <types>
    <dataTypes/>
    <pous>
"""
FOOTER = """    </pous>
  </types>
  <instances>
    <configurations>
      <configuration name="cfg">
        <resource name="res">
          <task name="t" priority="1" interval="T#10ms">
            <pouInstance name="inst" typeName="prog"/>
          </task>
        </resource>
      </configuration>
    </configurations>
  </instances>
</project>
"""
CONFIG_ST = """CONFIGURATION cfg
    RESOURCE res ON PLC
        TASK t(INTERVAL := T#10ms, PRIORITY := 1);
        PROGRAM inst WITH t : prog;
    END_RESOURCE
END_CONFIGURATION
"""


@dataclass
class GraphicProject:
    seed: int
    kind: str                      # "LD" or "FBD"
    xml: str
    st: str
    inputs: list                   # (cycle, name, value text)
    outputs: list                  # variable names compared
    cycles: int
    features: set = field(default_factory=set)


class _Body:
    def __init__(self):
        self.elements: list[str] = []
        self.next_id = 1

    def new_id(self) -> int:
        i = self.next_id
        self.next_id += 1
        return i


def _conn(refs):
    inner = "".join(f'<connection refLocalId="{r}"{"" if p is None else f" formalParameter={chr(34)}{p}{chr(34)}"}/>'
                    for r, p in refs)
    return f"<connectionPointIn>{inner}</connectionPointIn>"


def _var_decls(section, names_types):
    if not names_types:
        return ""
    rows = "".join(f'<variable name="{n}"><type>{t if t.startswith("<") else "<" + t + "/>"}'
                   f'</type></variable>' for n, t in names_types)
    return f"<{section}>{rows}</{section}>"


# ------------------------------------------------------------------- LD
def _ld(rng: random.Random, p: GraphicProject):
    bools_in = [f"i{k}" for k in range(4)]
    coils = [f"q{k}" for k in range(rng.randint(3, 6))]
    body = _Body()
    st_decl, st_lines = [], []
    trig = [0]
    y = [0]

    def trig_name(kind):
        trig[0] += 1
        name = f"ref_{'r' if kind == 'rising' else 'f'}{trig[0]}"
        st_decl.append((name, "R_TRIG" if kind == "rising" else "F_TRIG"))
        return name

    rail = body.new_id()
    body.elements.append(f'<leftPowerRail localId="{rail}"><position x="0" y="0"/>'
                         f'<connectionPointOut formalParameter=""/></leftPowerRail>')

    def tree(depth):
        r = rng.random()
        if depth > 2 or r < 0.45:
            var = rng.choice(bools_in + coils)
            kind = rng.choices(["normal", "negated", "rising", "falling"], [6, 3, 1, 1])[0]
            return ("c", var, kind)
        return ("s" if r < 0.75 else "p", tree(depth + 1), tree(depth + 1))

    def build(t, ins, ins_st, pre):
        """XML elements for tree t fed by the connections ins; returns
        (output refs, ST flow expression)."""
        if t[0] == "c":
            _, var, kind = t
            i = body.new_id()
            y[0] += 1
            attrs = ' negated="true"' if kind == "negated" else \
                f' edge="{kind}"' if kind in ("rising", "falling") else ""
            body.elements.append(f'<contact localId="{i}"{attrs}><position x="{10 * len(ins)}" '
                                 f'y="{y[0]}"/>{_conn(ins)}<connectionPointOut/>'
                                 f'<variable>{var}</variable></contact>')
            p.features.add(f"ld_contact_{kind}")
            if kind in ("rising", "falling"):
                n = trig_name(kind)
                pre.append(f"{n}(CLK := {var});")
                term = f"{n}.Q"
            else:
                term = f"NOT {var}" if kind == "negated" else var
            return [(i, None)], term if ins_st == "TRUE" else f"({ins_st} AND {term})"
        if t[0] == "s":
            r1, e1 = build(t[1], ins, ins_st, pre)
            return build(t[2], r1, e1, pre)
        p.features.add("ld_parallel")
        r1, e1 = build(t[1], ins, ins_st, pre)
        r2, e2 = build(t[2], ins, ins_st, pre)
        return r1 + r2, f"({e1} OR {e2})"

    for rung in range(rng.randint(2, 6)):
        y[0] = rung * 100
        pre: list[str] = []
        outs, flow = build(tree(0), [(rail, None)], "TRUE", pre)
        coil = rng.choice(coils)
        kind = rng.choices(["normal", "negated", "set", "reset", "rising", "falling"],
                           [5, 2, 2, 2, 1, 1])[0]
        p.features.add(f"ld_coil_{kind}")
        attrs = {"normal": "", "negated": ' negated="true"', "set": ' storage="set"',
                 "reset": ' storage="reset"', "rising": ' edge="rising"',
                 "falling": ' edge="falling"'}[kind]
        ci = body.new_id()
        body.elements.append(f'<coil localId="{ci}"{attrs}><position x="500" y="{y[0]}"/>'
                             f'{_conn(outs)}<connectionPointOut/><variable>{coil}</variable>'
                             f'</coil>')
        st_lines += pre
        if kind == "normal":
            st_lines.append(f"{coil} := {flow};")
        elif kind == "negated":
            st_lines.append(f"{coil} := NOT {flow};")
        elif kind in ("set", "reset"):
            st_lines.append(f"IF {flow} THEN {coil} := {'TRUE' if kind == 'set' else 'FALSE'}; "
                            f"END_IF;")
        else:
            n = trig_name(kind)
            st_lines += [f"{n}(CLK := {flow});", f"{coil} := {n}.Q;"]
    rr = body.new_id()
    body.elements.append(f'<rightPowerRail localId="{rr}"><position x="600" y="0"/>'
                         f'<connectionPointIn/></rightPowerRail>')
    p.outputs = coils
    return (bools_in, [(c, "BOOL") for c in coils], [], body, "LD", st_decl, st_lines)


# ------------------------------------------------------------------ FBD
FUNCS = {  # name: (input pins, input kind, output kind)
    "AND": (("IN1", "IN2"), "b", "b"), "OR": (("IN1", "IN2"), "b", "b"),
    "XOR": (("IN1", "IN2"), "b", "b"), "NOT": (("IN",), "b", "b"),
    "ADD": (("IN1", "IN2"), "i", "i"), "SUB": (("IN1", "IN2"), "i", "i"),
    "MAX": (("IN1", "IN2"), "i", "i"), "MIN": (("IN1", "IN2"), "i", "i"),
    "GT": (("IN1", "IN2"), "i", "b"), "EQ": (("IN1", "IN2"), "i", "b"),
    "LE": (("IN1", "IN2"), "i", "b"), "SEL": (("G", "IN0", "IN1"), "gi", "i"),
}
FBS = {  # type: (inputs with kinds, outputs with kinds)
    "CTU": ((("CU", "b"), ("R", "b"), ("PV", "i")), (("Q", "b"), ("CV", "i"))),
    "TON": ((("IN", "b"), ("PT", "t")), (("Q", "b"),)),
    "R_TRIG": ((("CLK", "b"),), (("Q", "b"),)),
    "SR": ((("S1", "b"), ("R", "b")), (("Q1", "b"),)),
}


def _fbd(rng: random.Random, p: GraphicProject):
    bools_in = [f"i{k}" for k in range(4)]
    ints_in = [f"n{k}" for k in range(2)]
    body = _Body()
    # nodes: (kind b/i, xml ref (id, pin), st expr); sources first
    nodes = {"b": [], "i": []}
    st_decl, st_lines = [], []
    order = []              # (xml element text) in data order, shuffled positions later
    stmts = []              # (index in order, index in st_lines) of each statement
    for v in bools_in:
        i = body.new_id()
        order.append(f'<inVariable localId="{i}"><position x="X" y="Y"/><connectionPointOut/>'
                     f'<expression>{v}</expression></inVariable>')
        nodes["b"].append(((i, None), v))
    for v in ints_in + ["3", "-2"]:
        i = body.new_id()
        order.append(f'<inVariable localId="{i}"><position x="X" y="Y"/><connectionPointOut/>'
                     f'<expression>{v}</expression></inVariable>')
        nodes["i"].append(((i, None), v))
    tmp = [0]
    instances = []
    for _ in range(rng.randint(4, 12)):
        if rng.random() < 0.3:
            typ = rng.choice(list(FBS))
            ins, outs = FBS[typ]
            name = f"fb{len(instances)}"
            instances.append((name, typ))
            i = body.new_id()
            pins, args = [], []
            for pin, k in ins:
                if k == "t":
                    ref, expr = None, rng.choice(["T#20ms", "T#30ms", "T#50ms"])
                    ti = body.new_id()
                    order.append(f'<inVariable localId="{ti}"><position x="X" y="Y"/>'
                                 f'<connectionPointOut/><expression>{expr}</expression>'
                                 f'</inVariable>')
                    ref = (ti, None)
                else:
                    ref, expr = rng.choice(nodes[k][-6:])
                neg = k == "b" and rng.random() < 0.15
                if neg:
                    p.features.add("fbd_negated_pin")
                pins.append(f'<variable formalParameter="{pin}"{" negated=" + chr(34) + "true" + chr(34) if neg else ""}>'
                            f'{_conn([ref])}</variable>')
                args.append(f"{pin} := {'NOT ' if neg else ''}{expr}")
            outs_xml = "".join(f'<variable formalParameter="{o}"><connectionPointOut/></variable>'
                               for o, _ in outs)
            order.append(f'<block localId="{i}" typeName="{typ}" instanceName="{name}">'
                         f'<position x="X" y="Y"/><inputVariables>{"".join(pins)}'
                         f'</inputVariables><inOutVariables/><outputVariables>{outs_xml}'
                         f'</outputVariables></block>')
            stmts.append((len(order) - 1, len(st_lines)))
            st_lines.append(f"{name}({', '.join(args)});")
            for o, k in outs:
                nodes[k].append(((i, o), f"{name}.{o}"))
            p.features.add(f"fbd_fb_{typ}")
            continue
        fn = rng.choice(list(FUNCS))
        pins_, kinds, out = FUNCS[fn]
        i = body.new_id()
        pins, args = [], []
        first_int = True
        for n_pin, pin in enumerate(pins_):
            k = "b" if kinds == "b" or (kinds == "gi" and n_pin == 0) else "i"
            pool = nodes[k][-6:]
            if k == "i" and first_int:
                # one input is typed (a variable or a computed value): the
                # type of a function of untyped literals alone is not
                # defined by its network (iec2kmod refuses it by name)
                pool = [n for n in nodes[k] if n[1] not in ("3", "-2")][-6:]
                first_int = False
            ref, expr = rng.choice(pool)
            neg = k == "b" and rng.random() < 0.15
            if neg:
                p.features.add("fbd_negated_pin")
            pins.append(f'<variable formalParameter="{pin}"{" negated=" + chr(34) + "true" + chr(34) if neg else ""}>'
                        f'{_conn([ref])}</variable>')
            args.append(f"{'NOT ' if neg else ''}{expr}")
        order.append(f'<block localId="{i}" typeName="{fn}"><position x="X" y="Y"/>'
                     f'<inputVariables>{"".join(pins)}</inputVariables><inOutVariables/>'
                     f'<outputVariables><variable formalParameter="OUT"><connectionPointOut/>'
                     f'</variable></outputVariables></block>')
        # the referee evaluates every function once, in data order, into a
        # variable of its own
        tmp[0] += 1
        t = f"f{tmp[0]}"
        st_decl.append((t, "BOOL" if out == "b" else "INT"))
        stmts.append((len(order) - 1, len(st_lines)))
        st_lines.append(f"{t} := {fn}({', '.join(args)});")
        nodes[out].append(((i, "OUT"), t))
        p.features.add(f"fbd_fn_{fn}")
    outputs = []
    produced = [n for k in ("b", "i") for n in nodes[k][len(bools_in if k == "b" else []):]]
    for k in ("b", "i"):
        cands = nodes[k][(len(bools_in) if k == "b" else len(ints_in) + 2):]
        for ref, expr in rng.sample(cands, min(len(cands), rng.randint(1, 3))):
            name = f"o{len(outputs)}"
            outputs.append((name, "BOOL" if k == "b" else "INT"))
            i = body.new_id()
            order.append(f'<outVariable localId="{i}"><position x="X" y="Y"/>{_conn([ref])}'
                         f'<expression>{name}</expression></outVariable>')
            stmts.append((len(order) - 1, len(st_lines)))
            st_lines.append(f"{name} := {expr};")
    del produced
    if rng.random() < 0.3:
        # the editor's execution order on every block and outVariable, a
        # random permutation: the referee runs the statements in that
        # order (a value read before its element ran is the previous
        # cycle's: the referee's variables keep it)
        p.features.add("fbd_execution_order")
        perm = list(range(len(stmts)))
        rng.shuffle(perm)
        lines = list(st_lines)
        for n, (k, (oi, li)) in enumerate(sorted(zip(perm, stmts))):
            order[oi] = order[oi].replace('localId=', f'executionOrderId="{k + 1}" localId=', 1)
            st_lines[n] = lines[li]
    # random drawing positions: the drawing order is not the data order
    for el in order:
        y = rng.randint(0, 1000)
        body.elements.append(el.replace('x="X" y="Y"', f'x="{rng.randint(0, 500)}" y="{y}"', 1))
    rng.shuffle(body.elements)
    p.outputs = [n for n, _ in outputs] + [f"{n}.Q" if t != "SR" else f"{n}.Q1"
                                           for n, t in instances]
    return (bools_in, outputs, ints_in, body, "FBD", st_decl,
            st_lines, instances)


def generate(seed: int, cycles: int = 40) -> GraphicProject:
    rng = random.Random(seed)
    p = GraphicProject(seed, "", "", "", [], [], cycles)
    res = _ld(rng, p) if rng.random() < 0.5 else _fbd(rng, p)
    bools_in, outs, ints_in, body, kind, st_decl, st_lines = res[:7]
    instances = res[7] if len(res) > 7 else []
    p.kind = kind
    inputs = [(b, "BOOL") for b in bools_in] + [(n, "INT") for n in ints_in]
    iface = (_var_decls("inputVars", inputs) + _var_decls("outputVars", outs) +
             _var_decls("localVars", [(n, f'<derived name="{t}"/>') for n, t in instances]))
    p.xml = (HEADER + f'      <pou name="prog" pouType="program"><interface>{iface}</interface>'
             f'<body><{kind}>\n' + "\n".join(body.elements) + f"\n</{kind}></body></pou>\n" +
             FOOTER)
    decl = ["PROGRAM prog", "VAR_INPUT"] + [f"    {n} : {t};" for n, t in inputs] + \
        ["END_VAR", "VAR_OUTPUT"] + [f"    {n} : {t};" for n, t in outs] + ["END_VAR"]
    hidden = st_decl + instances
    if hidden:
        decl += ["VAR"] + [f"    {n} : {t};" for n, t in hidden] + ["END_VAR"]
    p.st = "\n".join(decl + st_lines + ["END_PROGRAM", ""]) + CONFIG_ST
    for cycle in range(1, cycles + 1):
        for b in bools_in:
            if rng.random() < 0.3:
                p.inputs.append((cycle, b, rng.choice(["TRUE", "FALSE"])))
        for n in ints_in:
            if rng.random() < 0.2:
                p.inputs.append((cycle, n, str(rng.randint(-5, 5))))
    return p
