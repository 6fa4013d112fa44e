"""Bundled scenario files (TOML), resolvable by name: ``uvms-qp run bluerov2_demo``.

The format is described in ``docs/scenarios.md``.
"""
