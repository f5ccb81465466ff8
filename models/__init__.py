"""The symid model zoo: one model file per system (format in :mod:`symid.modelfile`) with its truth and data recipe.

Installed as the package ``symid.zoo_models``; load entries with ``symid.load_model(name)``.
"""
