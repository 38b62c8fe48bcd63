"""Direct addresses as names of their variables.

A located variable (``VAR_GLOBAL lamp AT %QX0.3``, a program's ``Level AT
%IW2``, a function block's ``AT %Q*`` completed by VAR_CONFIG) is one
variable of the process image with two names: its IEC path and its address
(checks/config.py fills ConfigInfo.addresses, one variable per address).
The simulator, the interpreter and plc-manager take either."""

from __future__ import annotations


def addresses_of(project) -> dict:
    """address -> IEC path of its variable, for the project's configuration."""
    cfgs = getattr(project, "configurations", None) or []
    return dict(getattr(cfgs[0], "addresses", {}) or {}) if cfgs else {}


def name_index(table, addresses=None) -> dict:
    """Upper-case name -> index into a variable table (entries with .path),
    with every address naming the entry of its variable.  An address that
    is itself an entry (a direct address of a program connection) stays
    that entry."""
    index = {e.path.upper(): i for i, e in enumerate(table)}
    for address, path in (addresses or {}).items():
        i = index.get(path.upper())
        if i is not None:
            index.setdefault(address.upper(), i)
    return index
