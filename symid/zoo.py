"""The model zoo: systems from the thesis with their true values and data recipes.

Each zoo model is one Python file in the top-level ``models/`` folder (shipped in the
wheel as the package ``symid.zoo_models``), written in the model-file format of
:mod:`symid.modelfile` (``model``, optionally ``known``, ``start``, ``scale``,
``bounds``, units) plus what only a simulation study has: ``truth``,
``make_data(model, truth, noise=None, seed=None)`` and ``recipe``.
:func:`load_model` reads a zoo name or the path of any model file.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from symid.errors import ModelError
from symid.modelfile import ModelFile, from_module, read_model_file

__all__ = ["ZooEntry", "list_models", "load_model"]


@dataclass(frozen=True, kw_only=True)
class ZooEntry(ModelFile):
    """A zoo model: a model file (:class:`~symid.modelfile.ModelFile`) plus its truth and data recipe.

    Attributes
    ----------
    name : str
        Zoo name (the file name without ``.py``).
    title : str
        One-line description.
    source : str
        Where it comes from (thesis equations).
    model : StateSpaceModel or SecondOrderModel
        The symbolic model.
    truth : dict of str to float
        True parameter values.
    recipe : str
        The data recipe in words (what ``data()`` simulates).
    make_data : callable
        ``make_data(model, truth, noise=None, seed=None)`` returning a data object.
    notes : str
        Remarks: transcription choices, discrepancies with the printed thesis.
    extra : dict
        Anything else the entry carries (e.g. printed matrices of the thesis).

    Examples
    --------
    >>> import symid as si
    >>> entry = si.load_model("mass_damper_2dof")
    >>> entry.truth["k1"], entry.model.output
    (2.0, 'position')
    >>> entry.data().H.shape                     # thesis §4-6-2: 30 frequencies, SISO
    (30, 1, 1)
    """

    truth: dict[str, float]
    recipe: str
    make_data: Callable[..., Any] = field(repr=False)
    extra: dict[str, Any] = field(default_factory=dict, repr=False)

    def data(self, noise: float | None = None, seed: int | None = None) -> Any:
        """Simulate the entry's data recipe from the truth (optionally with relative noise).

        Parameters
        ----------
        noise : float, optional
            Relative noise level (see the simulator the recipe uses); ``None`` gives
            exact data.
        seed : int, optional
            Seed of the noise.

        Returns
        -------
        FrequencyData, SpectralData, IOData or BlackBox
            Whatever the recipe produces (``recipe`` says which).
        """
        return self.make_data(self.model, self.truth, noise=noise, seed=seed)

    def summary(self) -> str:
        """Model, truth and recipe as readable text."""
        truth = "\n".join(f"  {k:>10s} = {v:.6g}" for k, v in self.truth.items())
        parts = [f"{self.name}: {self.title}", f"source: {self.source}", self.model.summary(),
                 *self._spec_lines(), f"truth:\n{truth}", f"data recipe: {self.recipe}"]
        if self.notes:
            parts.append(f"notes: {self.notes}")
        return "\n".join(parts)

    def to_dict(self) -> dict[str, Any]:
        """The entry's declarations, truth and recipe as plain JSON-ready values."""
        return {**super().to_dict(), "truth": dict(self.truth), "recipe": self.recipe, "notes": self.notes}


_ZOO_PACKAGE = "symid.zoo_models"


def _zoo_package():
    """The zoo package: installed as ``symid.zoo_models``, or ``models/`` of a source checkout.

    A wheel maps the top-level ``models/`` folder to ``symid.zoo_models``. When symid is
    imported from a source tree instead (``python -m symid.cli`` run in the repository
    root puts the checkout's ``symid/`` first on ``sys.path``), that mapping does not
    exist, so the checkout's ``models/`` folder is registered under the same name.
    """
    try:
        return importlib.import_module(_ZOO_PACKAGE)
    except ModuleNotFoundError as exc:
        if exc.name != _ZOO_PACKAGE:
            raise
    folder = Path(__file__).resolve().parents[1] / "models"
    init = folder / "__init__.py"
    if not init.is_file():
        raise ModelError(f"the model zoo is missing: no package {_ZOO_PACKAGE} and no {folder}; "
                         "reinstall symid with `pip install .`")
    spec = importlib.util.spec_from_file_location(_ZOO_PACKAGE, init, submodule_search_locations=[str(folder)])
    module = importlib.util.module_from_spec(spec)
    sys.modules[_ZOO_PACKAGE] = module
    spec.loader.exec_module(module)
    return module


def list_models() -> list[str]:
    """Names of the models in the zoo, sorted.

    Returns
    -------
    list of str
        Names accepted by :func:`load_model` (the ``models/`` files, without ``.py``).

    Examples
    --------
    >>> import symid as si
    >>> "belt_drive" in si.list_models()
    True
    """
    pkg = _zoo_package()
    return sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if not m.name.startswith("_"))


def load_model(name_or_path: str | Path) -> ModelFile:
    """Load a zoo model by name (``"belt_drive"``) or a model file by its path.

    Parameters
    ----------
    name_or_path : str or pathlib.Path
        A name listed by :func:`list_models`, or the path of a ``.py`` model file
        (format in :mod:`symid.modelfile`). A model file is Python code and is run:
        load only files you trust.

    Returns
    -------
    ModelFile
        A :class:`ZooEntry` (a ModelFile with ``truth``, ``recipe`` and ``data()``) for
        a zoo name or a file that defines ``truth`` and ``make_data``; otherwise a
        :class:`~symid.modelfile.ModelFile`.

    Raises
    ------
    ModelError
        If no such zoo model exists, or the file is missing, fails when run, defines no
        model or several, or declares values that do not fit its model.

    Examples
    --------
    >>> import symid as si
    >>> entry = si.load_model("belt_drive")
    >>> entry.model.parameter_names
    ('theta1', 'theta2', 'theta3', 'theta4')
    """
    text = str(name_or_path)
    path = Path(text)
    if text.endswith(".py") or path.is_file() or "/" in text or "\\" in text:
        return read_model_file(path)
    names = list_models()
    if text not in names:
        raise ModelError(f"no zoo model named {text!r}; available: {', '.join(names)} (or give the path of a "
                         "model file, ending in .py)")
    module = importlib.import_module(f"{_ZOO_PACKAGE}.{text}")
    return from_module(module, name=text, where=f"zoo model {text!r}", path=module.__file__)
