"""plc-manager: loads, swaps and stops iec2kmod kernel modules (sysfs + generic netlink)."""
