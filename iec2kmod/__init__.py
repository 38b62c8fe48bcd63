"""iec2kmod: IEC 61131-3 projects compiled into Linux PREEMPT_RT kernel modules."""

__version__ = "0.1.0"
