"""The symid model zoo: one file per system, each defining ``entry() -> symid.ZooEntry``.

Installed as the package ``symid.zoo_models``; load entries with ``symid.load_model(name)``.
"""
