"""Test tooling: fault injection into back-ends and soak runs (never imported by the library).

* :mod:`uvms_qp.testing.faults`: a back-end wrapper that misbehaves on command.
* :mod:`uvms_qp.testing.soak`: many closed-loop steps of the bundled demo under random faults.
* :mod:`uvms_qp.testing.sweep_faults`: sweep workers that die on a chosen run.
"""
