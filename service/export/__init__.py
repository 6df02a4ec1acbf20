"""Embedded export: a mechanism's solver as dependency-free C99 for controllers.

plan (what is exported: inputs, outputs, target, limits), kernels (the CasADi Functions of each
task and a Python twin of the C iteration), sources (the C library, its header, build files and
examples), library (writing and archiving one export). The linear state-space model lives with
vibration (service.vibration.state_space).
"""
