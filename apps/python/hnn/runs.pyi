# Types of hnn's runs (runs.py), for editors; tests/python/hnn_test.py checks that it names
# every name of __all__ and every public member of Run.
from os import PathLike
from typing import Any, Optional

import numpy as np

from ._hnn import Model

__all__: list[str]

def train(task: Optional[str] = None, model: Optional[str] = None, seed: Optional[int] = None,
          out: Optional[str | PathLike[str]] = None,
          resume: bool | str | PathLike[str] = False, **options: Any) -> Run: ...
def load_run(path: str | PathLike[str]) -> Run: ...

class Run:
    path: str
    metrics: dict[str, Any]
    def __init__(self, path: str | PathLike[str]) -> None: ...
    @property
    def loss_curve(self) -> dict[str, np.ndarray]: ...
    @property
    def rollouts(self) -> dict[str, dict[str, Any]]: ...
    @property
    def state_names(self) -> list[str]: ...
    @property
    def model(self) -> Model: ...
