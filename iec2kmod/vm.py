"""Alias kept for documents and scripts: ``python3 -m iec2kmod.vm`` runs the QEMU test harness, ``python3 -m iec2kmod.testing.vm``."""
import runpy
if __name__ == "__main__":
    runpy.run_module("iec2kmod.testing.vm", run_name="__main__", alter_sys=True)
