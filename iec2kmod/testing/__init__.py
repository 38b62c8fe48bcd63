"""Test support shipped with iec2kmod, not part of the compiler or the
manager: :mod:`iec2kmod.testing.vm` is the QEMU (TCG) guest harness the
tests under tests/qemu and the benchmarks boot the PREEMPT_RT kernel with
(``python3 -m iec2kmod.testing.vm check | prepare | run | shell``)."""
