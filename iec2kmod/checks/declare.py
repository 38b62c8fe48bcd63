"""Pass 'declare': user types and POU interfaces into the project's symbol
tables, duplicates reported.

``Declarer`` holds the types (a type spec to its Type, in dependency order)
and the POUs (their interfaces: VAR blocks, access paths, ENO, located
variables and the type of their address).  The constant expressions its
declarations hold (array bounds, string lengths, subrange limits,
enumeration values) and their initial values are evaluated and checked by
the mixin ``Constants`` (checks/consts.py), which the later passes use
through the Declarer too (``const_value``, ``constants_of``)."""

from __future__ import annotations

from .. import ast
from . import stdlib
from .consts import Constants
from .eno import _eno_var, _true, fb_eno
from .located import check_address_type
from .sfc import declare_steps
from .symbols import POUInfo, Project, Var
from .types import (BOOL, ELEMENTARY, ERROR, ArrayT, Elementary, EnumT, FBType, StringT, StructT, SubrangeT, Type)
from .types import identical as _identical

SECTIONS_IN_POU = {
    "FUNCTION": {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP"},
    "FUNCTION_BLOCK": {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP",
                       "VAR_EXTERNAL"},
    "PROGRAM": {"VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP", "VAR_EXTERNAL",
                "VAR_GLOBAL", "VAR_ACCESS"},
}

MAX_STRING = 65534


class Declarer(Constants):
    def __init__(self, project: Project, diags):
        self.p = project
        self.diags = diags
        self.enum_values: dict[str, list] = {}  # upper value name -> [EnumT]
        self._pending_types: dict[str, ast.TypeDef] = {}
        self._resolving: set = set()
        super().__init__()

    # ------------------------------------------------------------ errors
    def error(self, src, pos, msg):
        self.diags.error(src, pos, msg)

    def warning(self, src, pos, msg):
        self.diags.warning(src, pos, msg)

    # ------------------------------------------------------------ types
    def declare_types(self, units):
        for unit in units:
            for td in unit.types:
                key = td.name.upper()
                if key in self._pending_types or key in ELEMENTARY or key in ("STRING", "WSTRING"):
                    self.error(td.src, td.pos, f"type '{td.name}' is already defined" if
                               key in self._pending_types else
                               f"'{td.name}' is an elementary type and cannot be redefined")
                    continue
                if key in stdlib.FUNCTION_BLOCKS:
                    self.error(td.src, td.pos, f"'{td.name}' is a standard function block")
                    continue
                self._pending_types[key] = td
        # enumerations first, so their values can appear in other declarations
        for key, td in self._pending_types.items():
            if isinstance(td.spec, ast.EnumSpec):
                self.resolve_named(key)
        for key in list(self._pending_types):
            self.resolve_named(key)

    def resolve_named(self, key):
        if key in self.p.types:
            return self.p.types[key]
        td = self._pending_types.get(key)
        if td is None:
            return None
        if key in self._resolving:
            self.error(td.src, td.pos, f"type '{td.name}' is defined in terms of itself")
            self.p.types[key] = ERROR
            return ERROR
        self._resolving.add(key)
        t = self.type_of_spec(td.spec, td.src, name=td.name)
        self._resolving.discard(key)
        self.p.types[key] = t
        if td.init is not None and t is not ERROR:
            td.init = self.check_initializer(td.init, t, td.src)
            self.p.types.setdefault("__init__", {})[key] = td.init
        elif t is not ERROR and self.named_init(td.spec) is not None:
            # TYPE b : a; END_TYPE -- b starts where a starts
            self.p.types.setdefault("__init__", {})[key] = self.named_init(td.spec)
        return t

    def named_init(self, spec):
        """The declared initial value of the user type a spec names, if any
        (an alias of an elementary, string or array type is the aliased type
        itself, so its initial value has to travel with the variable)."""
        if isinstance(spec, ast.NamedSpec) and spec.name:
            return self.p.types.get("__init__", {}).get(spec.name.upper())
        return None

    def lookup_type(self, name, src, pos, report=True):
        if name is None:
            return None
        key = name.upper()
        if key in ELEMENTARY:
            return ELEMENTARY[key]
        t = self.resolve_named(key)
        if t is not None:
            return t
        if key in self.p.pous and self.p.pous[key].kind == "FUNCTION_BLOCK":
            return FBType(self.p.pous[key].name, self.p.pous[key])
        if key in stdlib.FUNCTION_BLOCKS:
            if key not in self.p.std_fbs:
                self.p.std_fbs[key] = FBType(key, stdlib.FUNCTION_BLOCKS[key])
            return self.p.std_fbs[key]
        if report:
            if key in self.p.pous:
                self.error(src, pos, f"'{name}' is a {self.p.pous[key].kind.lower().replace('_', ' ')}"
                                     ", not a type")
            elif key in ("CHAR", "WCHAR"):
                self.error(src, pos, f"unknown type '{name}' (CHAR and WCHAR are ed.3 types that "
                                     "iec2kmod does not support: use BYTE/WORD, or STRING[1] "
                                     "and WSTRING[1])")
            else:
                self.error(src, pos, f"unknown type '{name}'")
        return None

    def type_of_spec(self, spec, src, name=None) -> Type:
        if isinstance(spec, ast.NamedSpec):
            t = self.lookup_type(spec.name, src, spec.pos)
            return t if t is not None else ERROR
        if isinstance(spec, ast.StringSpec):
            length = 254
            if spec.length is not None:
                length = self.const_int(spec.length, src, "string length")
                if length is None:
                    return ERROR
                if not 1 <= length <= MAX_STRING:
                    self.error(src, spec.length.pos,
                               f"string length must be 1..{MAX_STRING}, not {length}")
                    return ERROR
            return StringT(length, spec.wide)
        if isinstance(spec, ast.SubrangeSpec):
            base = self.lookup_type(spec.base, src, spec.pos)
            if base is None:
                return ERROR
            if not (isinstance(base, Elementary) and base.cat in ("sint", "uint")):
                self.error(src, spec.pos, f"a subrange needs an integer base type, not {base.name}")
                return ERROR
            lo = self.const_int(spec.low, src, "subrange limit")
            hi = self.const_int(spec.high, src, "subrange limit")
            if lo is None or hi is None:
                return ERROR
            rng = base.range
            if lo > hi:
                self.error(src, spec.low.pos, f"empty subrange {lo}..{hi}")
                return ERROR
            if lo < rng[0] or hi > rng[1]:
                self.error(src, spec.low.pos, f"subrange {lo}..{hi} exceeds {base.name}")
                return ERROR
            return SubrangeT(name or f"{base.name}({lo}..{hi})", base, lo, hi)
        if isinstance(spec, ast.EnumSpec):
            base = None
            if spec.base:
                base = self.lookup_type(spec.base, src, spec.pos)
                if base is None:
                    return ERROR
                if not (isinstance(base, Elementary) and base.cat in ("sint", "uint", "bit")):
                    self.error(src, spec.pos,
                               f"an enumeration's base type must be an integer, not {base.name}")
                    return ERROR
            t = EnumT(name or "enum", base)
            nxt = 0
            seen_vals = {}
            for vname, vexpr, vpos in spec.values:
                if vname.upper() in t.values:
                    self.error(src, vpos, f"duplicate enumeration value '{vname}'")
                    continue
                if vexpr is not None:
                    v = self.const_int(vexpr, src, "enumeration value")
                    if v is None:
                        continue
                    nxt = v
                if base is not None and not base.range[0] <= nxt <= base.range[1]:
                    self.error(src, vpos, f"value {nxt} of '{vname}' does not fit {base.name}")
                if nxt in seen_vals:
                    self.error(src, vpos, f"'{vname}' has the same value {nxt} as "
                                          f"'{seen_vals[nxt]}'")
                seen_vals[nxt] = vname
                t.values[vname.upper()] = (vname, nxt)
                self.enum_values.setdefault(vname.upper(), []).append(t)
                nxt += 1
            return t
        if isinstance(spec, ast.ArraySpec):
            dims = []
            for lo_e, hi_e in spec.ranges:
                lo = self.const_int(lo_e, src, "array bound")
                hi = self.const_int(hi_e, src, "array bound")
                if lo is None or hi is None:
                    return ERROR
                if lo > hi:
                    self.error(src, lo_e.pos, f"empty array range {lo}..{hi}")
                    return ERROR
                dims.append((lo, hi))
            elem = self.type_of_spec(spec.element, src)
            if elem is ERROR:
                return ERROR
            t = ArrayT(dims, elem)
            if t.count > 1 << 24:
                self.error(src, spec.pos, f"array of {t.count} elements is too large")
                return ERROR
            return t
        if isinstance(spec, ast.StructSpec):
            t = StructT(name or "struct")
            for m in spec.members:
                mname, mpos = m.names[0]
                if mname.upper() in t.fields:
                    self.error(src, mpos, f"duplicate structure member '{mname}'")
                    continue
                if m.location:
                    self.error(src, mpos, "located structure members are not supported: "
                                          "declare a located global instead")
                mt = self.type_of_spec(m.spec, src)
                if isinstance(mt, FBType):
                    self.error(src, m.spec.pos, "a structure cannot contain a function block")
                    mt = ERROR
                if m.init is not None and mt is not ERROR:
                    m.init = self.check_initializer(m.init, mt, src)
                t.fields[mname.upper()] = (mname, mt, m.init if m.init is not None
                                           else self.named_init(m.spec))
            return t
        raise AssertionError(f"unknown spec {spec!r}")

    # ------------------------------------------------------------ POUs
    def declare_pous(self, units):
        self.collect_config_constants(units)
        for unit in units:
            for node in unit.pous:
                key = node.name.upper()
                if key in self.p.pous:
                    self.error(node.src, node.pos, f"'{node.name}' is already defined")
                    continue
                if key in self._pending_types:
                    self.error(node.src, node.pos, f"'{node.name}' is already defined as a type")
                    continue
                if stdlib.ed3_only(key):
                    self.warning(node.src, node.pos,
                                 f"'{node.name}' is a standard "
                                 f"{'function block' if key in stdlib.FUNCTION_BLOCKS else 'function'}"
                                 " of IEC 61131-3 ed.3 only: this project's "
                                 f"{node.kind.lower().replace('_', ' ')} of that name (ed.2 "
                                 "code) replaces it")
                elif node.kind == "FUNCTION" and stdlib.implementation_conversion(key):
                    self.warning(node.src, node.pos,
                                 f"FUNCTION '{node.name}' replaces this implementation's "
                                 f"conversion of that name (not a standard function of ed.2: "
                                 f"Table 22 leaves *_TO_** to the implementation, Table 30 names "
                                 f"only DT_TO_TOD and DT_TO_DATE between time types)")
                elif stdlib.is_std_function(key) or key in stdlib.FUNCTION_BLOCKS:
                    self.error(node.src, node.pos,
                               f"'{node.name}' is the name of a standard function or block")
                    continue
                if key in ELEMENTARY:
                    self.error(node.src, node.pos, f"'{node.name}' is an elementary type")
                    continue
                self.p.pous[key] = POUInfo(node.kind, node.name, node=node, src=node.src)
        self._access = []
        for pou in self.p.pous.values():
            self.declare_interface(pou)
        # after every interface: a path may name a member of an instance of
        # a block declared later, or its ENO (implicit_eno)
        for pou, block in self._access:
            self.program_access(pou, block)

    def declare_interface(self, pou: POUInfo):
        node = pou.node
        src = node.src
        if pou.kind == "FUNCTION":
            with self.constants_of(self.pou_scope(pou)):
                pou.result = self.type_of_spec(node.result, src)
            if isinstance(pou.result, FBType):
                self.error(src, node.result.pos, "a function cannot return a function block")
                pou.result = ERROR
            pou.vars[pou.key] = Var(pou.name, pou.result, "RESULT", node.pos, src, owner=pou)
        allowed = SECTIONS_IN_POU[pou.kind]
        access = []
        with self.constants_of(self.pou_scope(pou)) as scope:
            for block in node.blocks:
                if block.kind not in allowed:
                    self.error(src, block.pos, f"{block.kind} is not allowed in a "
                                               f"{pou.kind.lower().replace('_', ' ')}")
                    continue
                if block.kind == "VAR_ACCESS":
                    access.append(block)
                    continue
                self.declare_block(block, pou, src, pou.vars)
        self.mark_used(scope, pou.vars)
        self._access += [(pou, block) for block in access]
        self.declare_eno(pou)
        if node.sfc is not None:
            declare_steps(self, pou)
        for v in pou.vars.values():
            if v.section == "VAR_INPUT":
                pou.inputs.append(v)
            elif v.section == "VAR_OUTPUT" and v not in pou.outputs:
                pou.outputs.append(v)
            elif v.section == "VAR_IN_OUT":
                pou.inouts.append(v)

    def program_access(self, pou: POUInfo, block):
        """VAR_ACCESS in a PROGRAM (ed.2 2.7.1, program_access_decls):
        ``name : variable : type READ_ONLY|READ_WRITE`` names a variable of
        the program (or a member of one of its structures or FB instances)
        for access from outside; the type must be the variable's own and a
        CONSTANT can only be READ_ONLY.  Recorded in pou.access as
        (name, path, Var, direction)."""
        src = pou.src
        for d in block.decls:
            key = d.name.upper()
            if key in pou.vars or any(a[0].upper() == key for a in pou.access):
                self.error(src, d.pos, f"access path '{d.name}' is already declared in "
                                       f"{pou.name}")
                continue
            t = self.type_of_spec(d.spec, src)
            if d.path.startswith("%"):
                self.error(src, d.pos, f"access path '{d.name}': a program's access path names "
                                       f"one of its variables, not {d.path} (declare an access "
                                       "path to a located variable in the configuration's "
                                       "VAR_ACCESS)")
                continue
            parts = d.path.split(".")
            v, t_cur = None, None
            for n, part in enumerate(parts):
                if part.isdigit():
                    self.error(src, d.pos, f"access path '{d.name}': a bit ({d.path}) cannot "
                                           "be accessed by name")
                    v = None
                    break
                if n == 0:
                    v = pou.var(part)
                    if v is None or v.section == "RESULT":
                        self.error(src, d.pos, f"access path '{d.name}': {pou.name} has no "
                                               f"variable '{part}'")
                        break
                    t_cur = v.type
                elif isinstance(t_cur, FBType):
                    m = t_cur.pou.var(part)
                    if m is None and part.upper() == "ENO":
                        m = fb_eno(t_cur)
                    if m is None or m.section not in ("VAR_INPUT", "VAR_OUTPUT"):
                        self.error(src, d.pos, f"access path '{d.name}': '{part}' is not an "
                                               f"input or output of {t_cur.name}")
                        v = None
                        break
                    t_cur = m.type
                elif isinstance(t_cur, StructT) and part.upper() in t_cur.fields:
                    t_cur = t_cur.fields[part.upper()][1]
                else:
                    self.error(src, d.pos, f"access path '{d.name}': {'.'.join(parts[:n])} "
                                           f"has no member '{part}'")
                    v = None
                    break
            if v is None:
                continue
            if t is not ERROR and not _identical(t_cur, t):
                self.error(src, d.spec.pos, f"access path '{d.name}' is declared {t.name} but "
                                            f"{d.path} is {t_cur.name}")
                continue
            if v.constant and d.direction == "READ_WRITE":
                self.error(src, d.pos, f"{d.path} is CONSTANT: its access path must be READ_ONLY")
                continue
            v.used = True
            pou.access.append((d.name, d.path, v, d.direction))

    def declare_eno(self, pou: POUInfo):
        """ENO, the implicit BOOL output of every function and function
        block (ed.2 2.5.1.2, ed.3 6.6.1.5): TRUE when the body starts, the
        body may set it FALSE, and a call's ENO => receives it.  Declared
        here when the body uses it (ENO := FALSE; IL ST ENO) without
        declaring it; a declared ENO output starts TRUE as well."""
        if pou.kind not in ("FUNCTION", "FUNCTION_BLOCK"):
            return
        node = pou.node
        # EN and ENO are the implicit parameters of every call: a variable
        # of the block named so would silently become them (a VAR_INPUT en
        # FALSE skips the whole body).  ENO declared as a BOOL output is
        # the standard's explicit form (ed.3 6.6.1.5) and stays.
        for name, v in pou.vars.items():
            if name == "EN" and v.section in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"):
                self.error(v.src, v.pos, f"a {v.section} named {v.name} in {pou.kind} "
                           f"{pou.name}: EN is the implicit enable input of every call "
                           "(EN := FALSE skips the body); rename the variable")
            elif name == "ENO" and v.section in ("VAR_INPUT", "VAR_IN_OUT"):
                self.error(v.src, v.pos, f"a {v.section} named {v.name} in {pou.kind} "
                           f"{pou.name}: ENO is the implicit enable output of every call; "
                           "rename the variable")
            elif name == "ENO" and v.section == "VAR_OUTPUT" and v.type is not BOOL \
                    and getattr(v.type, "name", None) != "ERROR":
                self.error(v.src, v.pos, f"ENO, the implicit enable output of {pou.name}, "
                           "is BOOL; rename the variable")
        v = pou.vars.get("ENO")
        if v is None:
            if _mentions([node.body, node.sfc], "ENO"):
                _eno_var(pou)       # its outputs are listed after this
            return
        if v.section == "VAR_OUTPUT" and v.type is BOOL and v.init is None:
            v.init = _true(v.pos)

    def declare_block(self, block, owner, src, table, allow_located=False):
        constant = "CONSTANT" in block.qualifiers
        retain = True if "RETAIN" in block.qualifiers else (
            False if "NON_RETAIN" in block.qualifiers else None)
        if constant and block.kind in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP"):
            self.error(src, block.pos, f"{block.kind} cannot be CONSTANT")
        if retain is not None and block.kind in ("VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL"):
            self.error(src, block.pos, f"{block.kind} cannot be RETAIN or NON_RETAIN")
        if "RETAIN" in block.qualifiers and "NON_RETAIN" in block.qualifiers:
            self.error(src, block.pos, "RETAIN and NON_RETAIN exclude each other")
        out = []
        for decl in block.decls:
            t = self.type_of_spec(decl.spec, src)
            if decl.edge:
                if block.kind != "VAR_INPUT":
                    self.error(src, decl.pos, f"{decl.edge} is allowed only on VAR_INPUT")
                elif t is not BOOL:
                    self.error(src, decl.spec.pos, f"{decl.edge} input must be BOOL")
            if isinstance(t, FBType):
                if block.kind in ("VAR_INPUT", "VAR_OUTPUT", "VAR_EXTERNAL", "VAR_GLOBAL") or \
                        (isinstance(owner, POUInfo) and owner.kind == "FUNCTION"):
                    where = ("a function" if isinstance(owner, POUInfo) and
                             owner.kind == "FUNCTION" else block.kind)
                    hint = ""
                    if block.kind in ("VAR_GLOBAL", "VAR_EXTERNAL"):
                        names = ", ".join(f"'{n}'" for n, _ in decl.names)
                        hint = (f" ({names}): iec2kmod does not share function block "
                                "instances between programs; declare the instance in the VAR "
                                "of the program that calls it and share its inputs and "
                                "outputs through global variables")
                    self.error(src, decl.spec.pos,
                               f"function block instances cannot be declared in {where}{hint}")
            if decl.location:
                self.check_location_decl(decl, block, owner, src, t, allow_located)
            # a CONSTANT without an initial value holds its type's default
            # initial value (ed.2 2.4.2: the initial value is optional; ed.2
            # 2.3.3.1 gives every type a default), as MatIEC and CODESYS read it
            if decl.init is not None:
                if block.kind in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                    self.error(src, decl.init.pos, f"{block.kind} cannot have an initial value")
                elif t is not ERROR:
                    decl.init = self.check_initializer(decl.init, t, src)
            for name, pos in decl.names:
                key = name.upper()
                if key in table:
                    self.error(src, pos, f"'{name}' is already declared")
                    continue
                if isinstance(owner, POUInfo) and key == owner.key and owner.kind != "FUNCTION":
                    pass
                init = decl.init
                if init is None and block.kind not in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                    init = self.named_init(decl.spec)
                v = Var(name, t, block.kind, pos, src, constant=constant, retain=retain,
                        edge=decl.edge, location=decl.location, init=init, owner=owner)
                table[key] = v
                out.append(v)
        return out

    def check_location_decl(self, decl, block, owner, src, t, allow_located):
        addr = decl.location
        if not allow_located:
            kind = owner.kind if isinstance(owner, POUInfo) else None
            if block.kind == "VAR" and (kind == "PROGRAM" or
                                        kind == "FUNCTION_BLOCK" and addr.endswith("*")):
                # ed.2 program_declaration takes located_var_declarations (the
                # I/O of every OpenPLC program), and an incomplete location
                # (%I*, %Q*, %M*) in a program or function block is completed
                # by the configuration's VAR_CONFIG; the configuration checks
                # that one address belongs to one variable (checks/located.py)
                if not addr.endswith("*"):
                    check_address_type(self, src, decl.pos, addr, t)
                return
            name = decl.names[0][0]
            where = owner.kind.lower().replace("_", " ") if isinstance(owner, POUInfo) else \
                "this declaration"
            arrow = "=>" if addr[1] == "Q" else ":="
            if kind == "PROGRAM":
                self.error(src, decl.pos,
                           f"located variable '{name}' AT {addr} in {block.kind}: a program's "
                           "located variables are declared in VAR (ed.2 "
                           f"located_var_declarations); declare it there, or connect the "
                           f"{'output' if block.kind == 'VAR_OUTPUT' else 'input'}: PROGRAM "
                           f"inst WITH task : {owner.name} ({name} {arrow} {addr})")
                return
            if kind == "FUNCTION_BLOCK" and block.kind == "VAR":
                self.error(src, decl.pos,
                           f"located variable '{name}' AT {addr} in a function block: every "
                           "instance of the block would have that address, and one address is "
                           f"accessed by exactly one variable; declare it incomplete ({name} AT "
                           f"%{addr[1]}* : {t.name}) and give each instance its address in the "
                           "configuration's VAR_CONFIG, or make it an input or output of the "
                           "block and pass it from the program that calls it")
                return
            if isinstance(owner, POUInfo) and owner.kind == "PROGRAM":
                other = (f"or make '{name}' an input or output of the program and connect it: "
                         f"PROGRAM inst WITH task : {owner.name} ({name} {arrow} {addr})")
            else:
                other = (f"or make '{name}' an input or output of the {where} and pass it from "
                         "the program that calls it")
            self.error(src, decl.pos,
                       f"located variable '{name}' AT {addr} in a {where}: by the rule of "
                       "located variables, directly represented variables appear only in "
                       "configuration, resource and program declarations and in program "
                       "connections; "
                       f"declare it there (VAR_GLOBAL {name} AT {addr} : {t.name}; END_VAR) "
                       f"and reach it through VAR_EXTERNAL {name}, {other}")
            return
        if addr.endswith("*"):
            self.error(src, decl.pos, f"incomplete address {addr} is allowed only in the VAR of programs and "
                                      "function blocks "
                                      "(completed by VAR_CONFIG)")
            return
        check_address_type(self, src, decl.pos, addr, t)


def _mentions(node, name: str) -> bool:
    """Does a POU body (statements, IL instructions, expressions) refer to
    the variable ``name`` (upper case)?"""
    stack = [node]
    while stack:
        n = stack.pop()
        if n is None or isinstance(n, (str, int, float, bool)):
            continue
        if isinstance(n, (list, tuple)):
            stack.extend(n)
            continue
        if isinstance(n, ast.Ref):
            if n.name.upper() == name:
                return True
            stack.extend(v for k, v, _ in n.accessors if k == "index")
            continue
        if isinstance(n, ast.Arg):
            stack.append(n.value)
            continue
        if isinstance(n, ast.Call):
            stack.extend(n.args)
            continue
        if isinstance(n, (ast.Expr, ast.Node)):
            for cls in type(n).__mro__:
                for slot in getattr(cls, "__slots__", ()):
                    if slot not in ("pos", "type", "const", "src", "call", "cr_in", "cr_out"):
                        stack.append(getattr(n, slot, None))
    return False
