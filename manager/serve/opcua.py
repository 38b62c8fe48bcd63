# SPDX-License-Identifier: MIT
"""OPC UA server (asyncua) on the model.

Address space (namespace "urn:iec2kmod:<configuration>", also the
application URI, so index 1 in the NamespaceArray: clients find it by URI;
string node ids ``ns=1;s=<path>`` so they stay the same across a swap that
keeps the interface; an enumeration type ``type:<name>``):
Objects/<configuration>/
    Build (InterfaceHash, SourceHash), Globals/, DirectVariables/,
    AccessPaths/ (one variable per VAR_ACCESS path, with its access),
    <resource>/Globals/, <resource>/<task>/{State, Cycles, Overruns,
    Faults, Fault}, <resource>/<task>/<instance>/<variables>
(function block instances and array elements are folders of their
members).

Writes: only to variables a client may write (model.client_writable),
only by a user whose role is "write"; checked with the rules of
``plc-manager write`` and sent to the kernel; a refused write answers
BadOutOfRange (range, subrange, enumeration, capacity), BadTypeMismatch
(a value of another type), BadNotWritable (read-only), BadUserAccessDenied
(a read-only user or anonymous).
"""

from __future__ import annotations

import collections.abc
import hashlib
import hmac
import logging
import os
import re
import secrets
from pathlib import Path
from typing import Dict, List, Optional

from ..errors import PLCError, UsageError
from .kernel import Kernel
from .model import Model, Refused, array_groups, from_ua, placement, to_ua, ua_type

log = logging.getLogger("plc_manager.serve.opcua")

# ---------------------------------------------------------------------------
# users file: one user a line, "name:role:scrypt$N$r$p$salt_hex$hash_hex"
# role is "read" (browse, read, subscribe) or "write" (also write)

SCRYPT = (2 ** 14, 8, 1)


def hash_password(password: str, salt: Optional[bytes] = None, n: int = SCRYPT[0]) -> str:
    salt = salt or secrets.token_bytes(16)
    _, r, p = SCRYPT
    h = hashlib.scrypt(password.encode(), salt=salt, n=n, r=r, p=p, dklen=32)
    return f"scrypt${n}${r}${p}${salt.hex()}${h.hex()}"


def check_password(password: str, stored: str) -> bool:
    try:
        algo, n, r, p, salt, want = stored.split("$")
        if algo != "scrypt":
            return False
        h = hashlib.scrypt(password.encode(), salt=bytes.fromhex(salt), n=int(n), r=int(r),
                           p=int(p), dklen=len(want) // 2)
    except (ValueError, TypeError):
        return False
    return hmac.compare_digest(h.hex(), want)


def read_users(path: str) -> Dict[str, tuple]:
    users = {}
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise UsageError(f"{path}: cannot read the users file: {e.strerror}") from None
    for no, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split(":")
        if len(parts) != 3 or parts[1] not in ("read", "write") or \
                not parts[2].startswith("scrypt$"):
            raise UsageError(f"{path}:{no}: expected name:read|write:scrypt$... "
                             f"(write lines with `plc-manager serve-user`)")
        users[parts[0]] = (parts[1], parts[2])
    return users


def add_user(path: str, name: str, role: str, password: str, n: int = SCRYPT[0]) -> None:
    if not name or ":" in name or role not in ("read", "write"):
        raise UsageError("a user name without ':' and a role read or write")
    lines = []
    p = Path(path)
    if p.exists():
        lines = [ln for ln in p.read_text().splitlines()
                 if ln.strip() and ln.split(":")[0] != name]
    lines.append(f"{name}:{role}:{hash_password(password, n=n)}")
    p.write_text("\n".join(lines) + "\n")
    os.chmod(p, 0o600)


# ---------------------------------------------------------------------------
# certificate

def ensure_certificate(cert: Path, key: Path, app_uri: str, host: str) -> None:
    """A self-signed certificate (DER) and its key (PEM) for the server,
    generated once."""
    if cert.exists() and key.exists():
        return
    from cryptography import x509
    from cryptography.x509.oid import ExtendedKeyUsageOID
    from asyncua.crypto import cert_gen
    k = cert_gen.generate_private_key()
    c = cert_gen.generate_self_signed_app_certificate(
        k, f"iec2kmod plc-manager@{host}", {"organizationName": "iec2kmod"},
        [x509.UniformResourceIdentifier(app_uri), x509.DNSName(host)],
        extended=[ExtendedKeyUsageOID.SERVER_AUTH, ExtendedKeyUsageOID.CLIENT_AUTH],
        days=3650)
    from cryptography.hazmat.primitives.serialization import Encoding
    cert.parent.mkdir(parents=True, exist_ok=True)
    key.write_bytes(cert_gen.dump_private_key_as_pem(k))
    os.chmod(key, 0o600)
    cert.write_bytes(c.public_bytes(Encoding.DER))


def ensure_shelf(directory: Path) -> Path:
    """asyncua's standard address space as a shelf file in *directory*
    (built once: building it costs seconds on a PC, minutes on a small
    CPU; loading it a fraction of a second).  asyncua looks for the file
    itself (or NAME.db); the dbm module may write NAME.dat/NAME.dir, so an
    empty NAME marks a complete shelf."""
    import asyncio
    import asyncua
    shelf = directory / f"asyncua-{getattr(asyncua, '__version__', 'x')}-aspace"
    if shelf.is_file() or shelf.with_suffix(".db").is_file():
        return shelf

    async def build():
        from asyncua import Server
        await Server().init(shelf)

    directory.mkdir(parents=True, exist_ok=True)
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        asyncio.run(build())
    else:
        raise RuntimeError("ensure_shelf: call it outside the event loop")
    shelf.touch()
    return shelf


_DIR_LINE = re.compile(r"^'([^'\\]*)', \((\d+), (\d+)\)$")


class _DumbShelfReader(collections.abc.Mapping):
    """A dbm.dumb database (NAME.dat and its index NAME.dir), read-only,
    its index parsed with a regular expression: dbm.dumb parses each line
    of the index with ast.literal_eval, 0.45 s for the 6,174 nodes of
    asyncua's standard address space on a PC, most of a minute under TCG
    emulation (the Pythons without gdbm use dbm.dumb)."""

    def __init__(self, base: str) -> None:
        import ast
        index = {}
        with open(base + ".dir", encoding="latin-1") as f:
            for line in f:
                m = _DIR_LINE.match(line.rstrip("\n"))
                if m:
                    index[m.group(1).encode("latin-1")] = (int(m.group(2)), int(m.group(3)))
                elif line.strip():
                    key, place = ast.literal_eval(line)
                    index[key.encode("latin-1")] = tuple(place)
        self._index = index
        self._dat = open(base + ".dat", "rb")

    def __getitem__(self, key: bytes) -> bytes:
        pos, size = self._index[key]
        self._dat.seek(pos)
        return self._dat.read(size)

    def __contains__(self, key) -> bool:
        return key in self._index

    def __iter__(self):
        return iter(self._index)

    def __len__(self) -> int:
        return len(self._index)

    def close(self) -> None:
        self._dat.close()


class _FastShelve:
    """Stands for the shelve module in asyncua's address space while it
    opens the standard address space's shelf (read-only)."""

    @staticmethod
    def open(filename, flag="c", protocol=None, writeback=False):
        import shelve
        if flag == "r" and os.path.isfile(filename + ".dir") and \
                os.path.isfile(filename + ".dat"):
            return shelve.Shelf(_DumbShelfReader(filename), protocol=protocol)
        return shelve.open(filename, flag, protocol, writeback)


async def init_server(server, shelf: Path) -> None:
    """``await server.init(shelf)``, the shelf's dbm.dumb index read fast
    (see _DumbShelfReader)."""
    from asyncua.server import address_space
    saved = address_space.shelve
    address_space.shelve = _FastShelve
    try:
        await server.init(shelf)
    finally:
        address_space.shelve = saved


# ---------------------------------------------------------------------------

class Users:
    """asyncua user manager on the users file (and anonymous, read-only,
    when allowed)."""

    def __init__(self, users: Dict[str, tuple], anonymous: bool) -> None:
        self.users = users
        self.anonymous = anonymous
        self.refused = 0
        # passwords verified once (scrypt is slow by design, and asyncua
        # asks in its event loop): user -> a keyed digest of the password
        self._key = secrets.token_bytes(32)
        self._verified: Dict[str, bytes] = {}

    def get_user(self, iserver, username=None, password=None, certificate=None):
        from asyncua.crypto.permission_rules import User, UserRole
        if username is None:
            return User(role=UserRole.Anonymous, name=None) if self.anonymous else None
        u = self.users.get(username)
        if u is not None and password is not None:
            mac = hmac.new(self._key, password.encode(), "sha256").digest()
            if hmac.compare_digest(self._verified.get(username, b""), mac):
                return User(role=UserRole.User, name=username)
        if u is None or password is None or not check_password(password, u[1]):
            self.refused += 1
            log.warning("opcua: login of %r refused", username)
            return None
        self._verified[username] = mac
        return User(role=UserRole.User, name=username)

    def may_write(self, user) -> bool:
        name = getattr(user, "name", None)
        return name is not None and self.users.get(name, ("read",))[0] == "write"


def _ruleset():
    """Users read and write (writes are checked per variable), anonymous
    (when allowed) reads, browses and subscribes."""
    from asyncua import ua
    from asyncua.crypto.permission_rules import (ADMIN_TYPES, USER_TYPES, PermissionRuleset,
                                                 UserRole)
    writes = {ua.NodeId(ua.ObjectIds.WriteRequest_Encoding_DefaultBinary),
              ua.NodeId(ua.ObjectIds.CallRequest_Encoding_DefaultBinary),
              ua.NodeId(ua.ObjectIds.HistoryUpdateRequest_Encoding_DefaultBinary)}

    class Rules(PermissionRuleset):
        def __init__(self):
            user = set(map(ua.NodeId, USER_TYPES))
            self.d = {UserRole.Admin: user | set(map(ua.NodeId, ADMIN_TYPES)),
                      UserRole.User: user, UserRole.Anonymous: user - writes}

        def check_validity(self, user, action_type_id, body):
            return action_type_id in self.d.get(user.role, set())

    return Rules()


def _cheap_monitored_copies() -> None:
    """asyncua deep-copies every value it hands to each monitored item
    (MonitoredItemValues.set_current_datavalue), 'to prevent referencing
    the inner value': two thirds of the server's time when 1,000
    subscribed variables change (measured: 0.67 -> 0.2 s per poll on the
    host).  The server's values are never changed in place here (each
    update is a new DataValue of a new Variant of an immutable Python
    value), so a shallow copy is enough."""
    import copy
    try:
        from asyncua.server.monitored_item_service import MonitoredItemValues
    except ImportError:
        return
    if getattr(MonitoredItemValues, "_iec2kmod_shallow", False):
        return

    def set_current_datavalue(self, cur_val):
        self.old_dvalue = self.current_dvalue
        self.current_dvalue = copy.copy(cur_val)

    MonitoredItemValues.set_current_datavalue = set_current_datavalue
    MonitoredItemValues._iec2kmod_shallow = True


class OpcUaServer:
    def __init__(self, model: Model, kernel: Kernel, url: str, *, writable_all: bool,
                 users: Dict[str, tuple], allow_anonymous: bool, security: str,
                 cert_dir: Path) -> None:
        self.model = model
        self.kernel = kernel
        self.url = url
        self.writable_all = writable_all
        self.users = Users(users, allow_anonymous)
        self.security = security            # "encrypt" | "none"
        self.cert_dir = cert_dir
        self.server = None
        self.nodes: Dict[str, object] = {}     # path -> node
        self.last: Dict[str, object] = {}
        self.task_nodes: Dict[str, Dict[str, object]] = {}
        self.path_of: Dict[object, str] = {}   # node id -> lower path
        self.enum_types: Dict[str, object] = {}   # lower IEC type name -> DataType node id
        self.flagged: Dict[str, int] = {}      # lower path -> the bad status it shows
        self.halted = False
        self.fresh_reads = 0
        self.writes = 0
        self.refused = 0

    # -- address space -------------------------------------------------
    async def start(self) -> None:
        import asyncua
        from asyncua import Server, ua
        from urllib.parse import urlparse
        host = urlparse(self.url).hostname or "localhost"
        _cheap_monitored_copies()
        s = Server(user_manager=self.users)
        self.cert_dir.mkdir(parents=True, exist_ok=True)
        shelf = self.cert_dir / f"asyncua-{getattr(asyncua, '__version__', 'x')}-aspace"
        fresh = not (shelf.is_file() or shelf.with_suffix(".db").is_file())
        if fresh:
            await s.init(shelf)
        else:
            await init_server(s, shelf)
        if fresh:
            shelf.touch()
        s.set_endpoint(self.url)
        s.set_server_name(f"iec2kmod {self.model.configuration}")
        app_uri = f"urn:iec2kmod:{self.model.configuration}"
        await s.set_application_uri(app_uri)
        tokens = [ua.UserNameIdentityToken]
        if self.users.anonymous:
            tokens.append(ua.AnonymousIdentityToken)
        s.set_identity_tokens(tokens)
        policies = [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt]
        if self.security == "none":
            policies.append(ua.SecurityPolicyType.NoSecurity)
        cert, key = self.cert_dir / "server-cert.der", self.cert_dir / "server-key.pem"
        ensure_certificate(cert, key, app_uri, host)
        await s.load_certificate(str(cert))
        await s.load_private_key(str(key))
        s.set_security_policy(policies, permission_ruleset=_ruleset())
        self.ns = await s.register_namespace(app_uri)
        self.server = s
        await self._build()
        self._hook_writes()
        self._hook_subscriptions()
        from asyncua.common.callback import CallbackType
        s.subscribe_server_callback(CallbackType.PreRead, self._pre_read)
        try:
            await s.start()
        except OSError as e:
            raise PLCError(f"opc ua {self.url}: cannot listen ({e.strerror or e}): the port "
                           f"is taken, or below 1024 without CAP_NET_BIND_SERVICE") from None
        self.started = True

    async def _build(self) -> None:
        from asyncua import ua
        s, ns, m = self.server, self.ns, self.model
        root = await s.nodes.objects.add_folder(ua.NodeId(m.configuration, ns), m.configuration)
        folders: Dict[tuple, object] = {(): root}

        async def folder(parts):
            parts = tuple(parts)
            if parts in folders:
                return folders[parts]
            parent = await folder(parts[:-1])
            nid = ua.NodeId("/".join(parts) + "/", ns)
            f = await parent.add_folder(nid, ua.QualifiedName(parts[-1], ns))
            folders[parts] = f
            return f

        build = await folder(["Build"])
        for name, val in (("InterfaceHash", m.interface_hash), ("SourceHash", m.source_hash),
                          ("Generator", m.generator)):
            await build.add_variable(ua.NodeId(f"Build/{name}", ns), name,
                                     ua.Variant(val, ua.VariantType.String))
        await build.add_variable(ua.NodeId("Build/Programs", ns), "Programs",
                                 ua.Variant(m.programs, ua.VariantType.String, is_array=True))
        for t in m.tasks:
            f = await folder([t.resource, t.name])
            nodes = {}
            for name, vt, init in (("State", ua.VariantType.String, "?"),
                                   ("Cycles", ua.VariantType.UInt64, 0),
                                   ("Overruns", ua.VariantType.UInt64, 0),
                                   ("Faults", ua.VariantType.UInt64, 0),
                                   ("Fault", ua.VariantType.String, ""),
                                   ("IntervalMs", ua.VariantType.Double,
                                    (t.interval_ns or 0) / 1e6)):
                nodes[name] = await f.add_variable(
                    ua.NodeId(f"{t.resource}.{t.name}/{name}", ns), name, ua.Variant(init, vt))
            self.task_nodes[f"{t.resource}.{t.name}".lower()] = nodes
        self.writable_nodes: Dict[str, str] = {}     # node id string -> path
        self.arrays = array_groups(m)
        in_array = {p for els in self.arrays.values() for p in els}
        self.array_of = {p.lower(): a for a, els in self.arrays.items() for p in els}
        self.array_nodes: Dict[str, object] = {}
        for path in m.order:
            if path in in_array:
                continue
            dirs, rest = placement(m, path)
            parent = await folder(dirs + rest[:-1])
            await self._variable(parent, path, path, rest[-1])
        for a, els in self.arrays.items():
            dirs, rest = placement(m, a)
            parent = await folder(dirs + rest[:-1])
            await self._array(parent, a, els, rest[-1])
        for a in m.access:
            parent = await folder(["AccessPaths"])
            await self._variable(parent, a.path, f"access:{a.name}", a.name, access=a)

    async def _variable(self, parent, path: str, sid: str, name: str, access=None) -> None:
        from asyncua import ua
        t = self.model.var(path)
        vt = _vtype(t)
        init = {"Boolean": False, "String": "", "Float": 0.0, "Double": 0.0,
                "Duration": 0.0}.get(ua_type(t), 0)
        if ua_type(t) == "DateTime":
            from .model import EPOCH
            init = EPOCH
        node = await parent.add_variable(ua.NodeId(sid, self.ns), ua.QualifiedName(name, self.ns),
                                         ua.Variant(init, vt), datatype=await self._datatype(t))
        if access is not None:
            w = access.read_write and t.writable
        else:
            w = self.model.client_writable(path, self.writable_all)
        if w:
            await node.set_writable(True)
            self.writable_nodes[node.nodeid.to_string()] = path
        if t.kind in "sw" and t.length is not None:
            await node.write_attribute(ua.AttributeIds.ArrayDimensions,
                                       ua.DataValue(ua.Variant([], ua.VariantType.UInt32)))
            await node.add_property(ua.NodeId(sid + "/MaxStringLength", self.ns),
                                    "MaxStringLength",
                                    ua.Variant(t.length, ua.VariantType.UInt32))
        self.nodes.setdefault(path.lower(), [])
        self.nodes[path.lower()].append(node)
        self.path_of[node.nodeid] = path.lower()

    async def _datatype(self, t):
        """The DataType of *t*'s variables: a built-in type, or for an
        enumeration a DataType node of its own, a subtype of Enumeration
        (node id ``type:<name>``, made once per IEC type), with its
        DataTypeDefinition (an EnumDefinition: the IEC names and values)
        and EnumStrings (values 0..n-1) or else EnumValues; its values
        travel as Int32 (OPC UA part 3, 8.14 and 5.8.3)."""
        from asyncua import ua
        if t.kind != "e" or not t.enum:
            return _datatype(t)
        name = t.type if t.type not in (None, "?") else t.path
        key = name.lower()
        if key in self.enum_types:
            return self.enum_types[key]
        items = sorted(t.enum.items(), key=lambda kv: kv[1])
        node = await self.server.nodes.enum_data_type.add_data_type(
            ua.NodeId(f"type:{name}", self.ns), ua.QualifiedName(name, self.ns))
        await node.write_data_type_definition(ua.EnumDefinition(Fields=[
            ua.EnumField(Value=v, DisplayName=ua.LocalizedText(n),
                         Description=ua.LocalizedText(n), Name=n) for n, v in items]))
        if [v for _, v in items] == list(range(len(items))):
            await node.add_property(
                ua.NodeId(f"type:{name}/EnumStrings", self.ns), ua.QualifiedName("EnumStrings", 0),
                ua.Variant([ua.LocalizedText(n) for n, _ in items], ua.VariantType.LocalizedText,
                           is_array=True), datatype=ua.NodeId(ua.ObjectIds.LocalizedText))
        else:
            await node.add_property(
                ua.NodeId(f"type:{name}/EnumValues", self.ns), ua.QualifiedName("EnumValues", 0),
                ua.Variant([ua.EnumValueType(Value=v, DisplayName=ua.LocalizedText(n),
                                             Description=ua.LocalizedText(n))
                            for n, v in items], ua.VariantType.ExtensionObject, is_array=True),
                datatype=ua.NodeId(ua.ObjectIds.EnumValueType))
        self.enum_types[key] = node.nodeid
        return node.nodeid

    async def _array(self, parent, path: str, elements: List[str], name: str) -> None:
        """One array variable for *elements* (ValueRank 1, ArrayDimensions
        [n]), node id the array's path; a write sets every element in one
        VAR_SET."""
        from asyncua import ua
        t = self.model.var(elements[0])
        vt = _vtype(t)
        init = {"Boolean": False, "String": "", "Float": 0.0, "Double": 0.0,
                "Duration": 0.0}.get(ua_type(t), 0)
        if ua_type(t) == "DateTime":
            from .model import EPOCH
            init = EPOCH
        node = await parent.add_variable(
            ua.NodeId(path, self.ns), ua.QualifiedName(name, self.ns),
            ua.Variant([init] * len(elements), vt, is_array=True),
            datatype=await self._datatype(t))
        await node.write_attribute(ua.AttributeIds.ValueRank,
                                   ua.DataValue(ua.Variant(1, ua.VariantType.Int32)))
        await node.write_attribute(ua.AttributeIds.ArrayDimensions, ua.DataValue(
            ua.Variant([len(elements)], ua.VariantType.UInt32)))
        if all(self.model.client_writable(p, self.writable_all) for p in elements):
            await node.set_writable(True)
            self.writable_nodes[node.nodeid.to_string()] = path
        self.array_nodes[path.lower()] = node
        self.path_of[node.nodeid] = path.lower()

    async def _sync_arrays(self, changed, stamps) -> None:
        """The array variables whose elements changed: the elements' last
        values, with the worst of their status codes."""
        from asyncua import ua
        for a in sorted({self.array_of[p] for p in changed if p in self.array_of}):
            els = [p.lower() for p in self.arrays[a]]
            if any(p not in self.last for p in els):
                continue
            codes = [self.flagged.get(p, ua.StatusCodes.Good) for p in els]
            code = next((c for c in codes if c != ua.StatusCodes.Good), ua.StatusCodes.Good)
            t = self.model.var(els[0])
            dv = ua.DataValue(ua.Variant([to_ua(t, self.last[p]) for p in els], _vtype(t),
                                         is_array=True),
                              StatusCode=ua.StatusCode(code),
                              SourceTimestamp=stamps.get(self._task_of(els[0])) or now(),
                              ServerTimestamp=now())
            await self.server.write_attribute_value(self.array_nodes[a.lower()].nodeid, dv)

    # -- writes ----------------------------------------------------------
    def _hook_writes(self) -> None:
        from asyncua import ua
        svc = self.server.iserver.attribute_service
        original = svc.write
        srv = self

        async def write(params, user=None):
            ours, others = [], []
            for i, wv in enumerate(params.NodesToWrite):
                if wv.NodeId.NamespaceIndex == srv.ns and \
                        wv.AttributeId == ua.AttributeIds.Value:
                    ours.append((i, wv))
                else:
                    others.append((i, wv))
            res: List[Optional[ua.StatusCode]] = [None] * len(params.NodesToWrite)
            if others:
                sub = ua.WriteParameters(NodesToWrite=[wv for _, wv in others])
                got = await original(sub, user) if user is not None else await original(sub)
                for (i, _), st in zip(others, got):
                    res[i] = st
            for i, wv in ours:
                res[i] = await srv._write_one(wv, user)
            return res

        svc.write = write

    async def _write_one(self, wv, user):
        from asyncua import ua
        sid = wv.NodeId.to_string()
        path = self.writable_nodes.get(sid)
        if path is None:
            self.refused += 1
            return ua.StatusCode(ua.StatusCodes.BadNotWritable)
        if user is not None and not self.users.may_write(user):
            from asyncua.crypto.permission_rules import UserRole
            if getattr(user, "role", None) != UserRole.Admin:
                self.refused += 1
                return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
        if self.halted:          # the kernel does not answer (a stop, a load under way)
            self.refused += 1
            return ua.StatusCode(ua.StatusCodes.BadServerHalted)
        v = wv.Value.Value
        elements = self.arrays.get(path) if path.lower() in self.array_nodes else None
        t = self.model.var(elements[0] if elements else path)
        if v is None or v.VariantType != _vtype(t) or \
                (elements is not None and (not isinstance(v.Value, list) or
                                           len(v.Value) != len(elements))):
            self.refused += 1
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        try:
            if elements is not None:
                items = [(p, from_ua(t, x)) for p, x in zip(elements, v.Value)]
            else:
                items = [(path, from_ua(t, v.Value))]
            await self.kernel.write(items)
        except Refused as e:
            self.refused += 1
            log.info("opcua write refused: %s", e)
            return ua.StatusCode({"range": ua.StatusCodes.BadOutOfRange,
                                  "type": ua.StatusCodes.BadTypeMismatch,
                                  "access": ua.StatusCodes.BadNotWritable}.get(
                                      e.why, ua.StatusCodes.BadInternalError))
        except PLCError as e:
            self.refused += 1
            log.warning("opcua write: %s", e)
            return ua.StatusCode(ua.StatusCodes.BadServerHalted)
        self.writes += 1
        return ua.StatusCode()

    # -- what is sampled ------------------------------------------------
    def wanted(self) -> List[str]:
        """The variables some client subscribes to now (a data change
        monitored item on one of its nodes): only these are polled."""
        from asyncua import ua
        aspace = self.server.iserver.aspace
        out = []
        for a, node in self.array_nodes.items():
            nd = aspace.get(node.nodeid)
            if nd is not None and nd.attributes[ua.AttributeIds.Value].datachange_callbacks:
                out += self.array_elements(a)
        for path, nodes in self.nodes.items():
            for node in nodes:
                nd = aspace.get(node.nodeid)
                if nd is not None and \
                        nd.attributes[ua.AttributeIds.Value].datachange_callbacks:
                    out.append(path)
                    break
        return out

    def array_elements(self, a: str) -> List[str]:
        """The lower paths of the elements of array *a* (lower path)."""
        for name, els in self.arrays.items():
            if name.lower() == a:
                return [p.lower() for p in els]
        return []

    async def _pre_read(self, event, _dispatcher) -> None:
        """A client reads values: the kernel's, fresh (they are not polled
        unless subscribed)."""
        params = getattr(event, "request_params", None)
        if params is None or not getattr(event, "is_external", True):
            return
        await self._refresh(params.NodesToRead)

    def _hook_subscriptions(self) -> None:
        """A new monitored item's first notification is the node's value:
        the kernel's, read then (not one of a cycle long past)."""
        svc = self.server.iserver.subscription_service
        original = svc.create_monitored_items
        srv = self

        async def create_monitored_items(params):
            await srv._refresh([i.ItemToMonitor for i in params.ItemsToCreate])
            return await original(params)

        svc.create_monitored_items = create_monitored_items

    async def _refresh(self, read_ids) -> None:
        """The values of the nodes *read_ids* (ReadValueIds) from the kernel."""
        from asyncua import ua
        if self.halted:
            return
        paths = set()
        for rv in read_ids:
            if rv.AttributeId == ua.AttributeIds.Value and \
                    rv.NodeId.NamespaceIndex == self.ns:
                p = self.path_of.get(rv.NodeId)
                if p is not None and p in self.array_nodes:
                    paths.update(self.array_elements(p))
                elif p is not None:
                    paths.add(p)
        if not paths:
            return
        self.fresh_reads += 1
        try:
            st = await self.kernel.status()
            snap = await self.kernel.read(sorted(paths))
        except PLCError as e:
            log.warning("opcua read: %s", e)
            return
        await self.update(snap, st)

    # -- updates ----------------------------------------------------------
    def _task_of(self, path: str) -> Optional[str]:
        """'res.task' running the program instance *path* belongs to."""
        parts = path.split(".")
        if len(parts) < 3:
            return None
        inst = self.model.instances.get(f"{parts[0]}.{parts[1]}".lower())
        if inst is None or not inst.get("task"):
            return None
        return f"{inst['resource']}.{inst['task']}".lower()

    @staticmethod
    def stamp_of(status, task: Optional[str]):
        """The source timestamp of a value of *task* ('res.task', None: a
        global): the end of the task's last cycle, as the kernel tells it
        (CLOCK_REALTIME; a global: the latest end among the tasks), else
        now (a kernel without it)."""
        import datetime
        ends = {t.path.lower(): t.last_end_ns for t in status.tasks()} if status else {}
        ns = ends.get(task) if task else max(ends.values(), default=0)
        if not ns:
            return now()
        return datetime.datetime.fromtimestamp(ns / 1e9, datetime.timezone.utc)

    async def update(self, snapshot: Dict[str, object], status) -> int:
        """New values of the variables that changed; returns how many.
        Each value is stamped with the end of its task's last cycle (the
        cycle whose values these are).  The variables of a program instance
        whose task is stopped on a fault are flagged BadOutOfService (the
        value then goes out null, OPC UA part 4, 7.7.1: clients keep the
        last one they had, frozen; its task's State and Fault say why),
        Good again once the task runs."""
        from asyncua import ua
        faulted = set()
        if status is not None:
            faulted = {t.path.lower() for t in status.tasks() if t.state == "fault"}
        stamps: Dict[Optional[str], object] = {}
        changed = set()
        n = 0
        for path, val in snapshot.items():
            if val is None:
                continue
            path = path.lower()
            task = self._task_of(path)
            bad = ua.StatusCodes.BadOutOfService if task in faulted else ua.StatusCodes.Good
            if self.flagged.get(path, ua.StatusCodes.Good) == bad and \
                    self.last.get(path) == val:
                continue
            if task not in stamps:
                stamps[task] = self.stamp_of(status, task)
            await self._set(path, val, bad, stamps[task])
            changed.add(path)
            n += 1
        # frozen: the variables of a faulted task not in this snapshot
        for path in list(self.last):
            if "/" in path:
                continue
            task = self._task_of(path)
            if task in faulted and \
                    self.flagged.get(path) != ua.StatusCodes.BadOutOfService:
                await self._set(path, self.last[path], ua.StatusCodes.BadOutOfService, now())
                changed.add(path)
        await self._sync_arrays(changed, stamps)
        if status is not None:
            for task in status.tasks():
                nodes = self.task_nodes.get(task.path.lower())
                if not nodes:
                    continue
                fault = ""
                if task.fault:
                    from ..ops import fault_text
                    fault = fault_text(task)
                for name, vt, v in (("State", ua.VariantType.String, task.state),
                                    ("Cycles", ua.VariantType.UInt64, task.cycles),
                                    ("Overruns", ua.VariantType.UInt64, task.overruns),
                                    ("Faults", ua.VariantType.UInt64, task.faults),
                                    ("Fault", ua.VariantType.String, fault)):
                    key = f"{task.path}/{name}"
                    if self.last.get(key) != v or self.halted:
                        self.last[key] = v
                        await self.server.write_attribute_value(
                            nodes[name].nodeid, ua.DataValue(ua.Variant(v, vt),
                                                             SourceTimestamp=now()))
        self.halted = False
        return n

    async def _set(self, path: str, val, code: int, stamp) -> None:
        from asyncua import ua
        self.last[path] = val
        t = self.model.var(path)
        if code == ua.StatusCodes.Good:
            self.flagged.pop(path, None)
        else:
            self.flagged[path] = code
        dv = ua.DataValue(ua.Variant(to_ua(t, val), _vtype(t)),
                          StatusCode=ua.StatusCode(code),
                          SourceTimestamp=stamp, ServerTimestamp=now())
        for node in self.nodes.get(path, ()):
            await self.server.write_attribute_value(node.nodeid, dv)

    async def halt(self) -> None:
        """The kernel does not answer (the configuration stopped or is being
        loaded): every value and the tasks' state say BadServerHalted until
        it answers again."""
        from asyncua import ua
        if self.halted:
            return
        self.halted = True
        code = ua.StatusCode(ua.StatusCodes.BadServerHalted)
        stamp = now()
        for a in self.array_nodes:
            for p in self.array_elements(a):
                self.flagged[p] = ua.StatusCodes.BadServerHalted
        everything = list(self.nodes.items()) + [(a, [n]) for a, n in self.array_nodes.items()]
        for path, nodes in everything:
            self.flagged[path] = ua.StatusCodes.BadServerHalted
            for node in nodes:
                await self.server.write_attribute_value(
                    node.nodeid, ua.DataValue(StatusCode=code, SourceTimestamp=stamp,
                                              ServerTimestamp=stamp))
        for nodes in self.task_nodes.values():
            await self.server.write_attribute_value(
                nodes["State"].nodeid, ua.DataValue(ua.Variant("halted", ua.VariantType.String),
                                                    SourceTimestamp=stamp))
        # the tasks' variables are written again once the kernel tells them
        # (a load under way may answer first without its tasks)
        for key in [k for k in self.last if "/" in k]:
            del self.last[key]

    async def stop(self) -> None:
        if self.server is not None and getattr(self, "started", False):
            await self.server.stop()


def _vtype(t):
    """The variant type of *t*'s values (a Duration is a Double)."""
    from asyncua import ua
    name = ua_type(t)
    return getattr(ua.VariantType, "Double" if name == "Duration" else name)


def _datatype(t):
    from asyncua import ua
    name = ua_type(t)
    return ua.NodeId(getattr(ua.ObjectIds, name))


def now():
    import datetime
    return datetime.datetime.now(datetime.timezone.utc)


__all__ = ["OpcUaServer", "add_user", "hash_password", "check_password", "read_users"]
