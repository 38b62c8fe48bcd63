"""Symbols: variables, enumeration values (what a name in a body resolves
to), POU interfaces, resources and the checked project that the code
generator consumes."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(eq=False)
class Var:
    """A declared variable.  ``section`` is the VAR kind (VAR, VAR_INPUT,
    VAR_OUTPUT, VAR_IN_OUT, VAR_EXTERNAL, VAR_GLOBAL, VAR_TEMP) or RESULT
    for a function's return value."""

    name: str
    type: object
    section: str
    pos: int | None = None
    src: object = None
    constant: bool = False
    retain: bool | None = None
    edge: str | None = None
    location: str | None = None
    init: object = None           # initializer AST (expression, ArrayInit, StructInit)
    owner: object = None          # POUInfo, ResourceInfo or ConfigInfo
    used: bool = False
    assigned: bool = False
    step: object = None           # ast.Step: the variable is an SFC step (checks/sfc.py)
    # a FUNCTION's ARRAY, STRUCT or STRING input its body writes: the
    # function works on a copy of the caller's value (codegen/pou.py)
    copied: bool = False

    @property
    def key(self) -> str:
        return self.name.upper()


@dataclass(eq=False)
class POUInfo:
    kind: str                    # FUNCTION, FUNCTION_BLOCK, PROGRAM
    name: str
    node: object = None          # ast.POU, None for standard FBs
    src: object = None
    result: object = None        # Type of a FUNCTION
    vars: dict = field(default_factory=dict)     # upper name -> Var, declaration order
    inputs: list = field(default_factory=list)   # [Var] VAR_INPUT in order
    outputs: list = field(default_factory=list)  # [Var] VAR_OUTPUT in order
    inouts: list = field(default_factory=list)   # [Var] VAR_IN_OUT in order
    standard: bool = False
    calls: set = field(default_factory=set)      # upper names of POUs this one uses
    uses_real: bool = False
    labels: dict = field(default_factory=dict)   # IL labels
    access: list = field(default_factory=list)   # VAR_ACCESS: [(name, path, Var, direction)]
    sfc: object = None           # checks.sfc.SFCInfo of an SFC body
    # a standard FB whose instances keep their ENO (stdlib.keeping_eno):
    # the runtime's struct and body inside one with an ENO member
    keeps_eno: bool = False

    @property
    def key(self) -> str:
        return self.name.upper()

    def var(self, name: str):
        return self.vars.get(name.upper())


@dataclass(eq=False)
class TaskInfo:
    name: str
    pos: int
    interval_ns: int | None = None
    priority: int = 0
    single: Var | None = None
    single_name: str | None = None
    # the watchdog ({watchdog ...} pragma in front of the TASK, see
    # checks/tasks.py): a cycle longer than watchdog_ns faults the task
    # (0: no limit); so do watchdog_overruns cycles in a row that end
    # after the next release (0: no limit)
    watchdog_ns: int = 0
    watchdog_overruns: int = 0


@dataclass(eq=False)
class ProgramInstance:
    name: str
    pou: POUInfo
    task: TaskInfo | None
    node: object
    inputs: list = field(default_factory=list)   # [(Var of the program, value expr)]
    outputs: list = field(default_factory=list)  # [(Var of the program, target expr)]
    externals: dict = field(default_factory=dict)  # upper external name -> global Var
    bindings: list = field(default_factory=list)   # [Binding]: every pointer member, any depth


@dataclass(frozen=True)
class Each:
    """A step into every element of an array of *count* (flattened) elements."""
    count: int


@dataclass(eq=False)
class Binding:
    """A pointer member of a program instance and the variable it refers to.

    ``steps`` leads from the program instance to the member: a Var is a member
    of the POU at that level (the last one is the VAR_EXTERNAL or VAR_IN_OUT
    itself), a str is a structure field, an Each is every element of an
    array.  ``target`` is a configuration or resource global, or a VAR_GLOBAL
    of the program (``in_program``)."""
    steps: tuple
    target: Var
    in_program: bool = False


@dataclass(eq=False)
class ResourceInfo:
    name: str
    processor: str | None
    node: object
    globals: dict = field(default_factory=dict)
    tasks: dict = field(default_factory=dict)
    programs: list = field(default_factory=list)

    def path(self, name: str) -> str:
        """IEC path of a name in this resource, as the variable table writes
        it (a configuration without RESOURCE has one implicit resource, whose
        name is not written)."""
        return f"{self.name}.{name}" if self.node.name else name


@dataclass(eq=False)
class ConfigInfo:
    name: str
    node: object
    src: object
    globals: dict = field(default_factory=dict)
    resources: list = field(default_factory=list)
    access: list = field(default_factory=list)
    # VAR_CONFIG initial values: [(ResourceInfo, ProgramInstance, [Var, ...], init)],
    # the Vars leading from the program instance to the variable (FB instances first)
    config_inits: list = field(default_factory=list)
    # every located variable by its address: address -> IEC path of the
    # variable (a global, r.inst.var of a program's located variable, the
    # VAR_CONFIG path of a completed %I* location); the tools take an
    # address wherever they take this path (sim, interpreter, plc-manager)
    addresses: dict = field(default_factory=dict)
    # address -> (type, frozenset of the resource names declaring or using
    # it): what the I/O map (iec2kmod/iomap.py) checks a binding against
    located: dict = field(default_factory=dict)
    # resource name (upper) -> iomap.ResourceIO: the devices and bindings of
    # the project's .iomap files
    io: dict = field(default_factory=dict)


@dataclass(eq=False)
class Project:
    """The checked model: what code generation starts from."""

    types: dict = field(default_factory=dict)        # upper name -> Type
    pous: dict = field(default_factory=dict)         # upper name -> POUInfo (user)
    configurations: list = field(default_factory=list)
    units: list = field(default_factory=list)
    # upper name -> the FBType of a standard FB: one per project, so that a
    # read of an instance's ENO changes the type of every instance
    std_fbs: dict = field(default_factory=dict)


class EnumValue:
    """What an unqualified or qualified enumeration value resolves to."""

    def __init__(self, enum, name):
        self.enum = enum
        self.name = name
        self.value = enum.values[name.upper()][1]
