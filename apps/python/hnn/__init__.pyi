# Types of the package hnn (__init__.py), for editors; tests/python/hnn_test.py checks that it
# names every name of __all__.
from os import PathLike

from . import autodiff as autodiff, systems as systems
from ._hnn import Error as Error, Model as Model, set_threads as set_threads, threads as threads
from .runs import Run as Run, load_run as load_run, train as train

__all__: list[str]

def HNN(dim: int, hidden: int | tuple[int, ...] | list[int] = (200, 200),
        activation: str = "tanh", *, dtype: str = "float64", seed: int = 0,
        angles: int = 0) -> Model: ...
def DHNN(dim: int, hidden: int | tuple[int, ...] | list[int] = (200, 200),
         activation: str = "tanh", *, dtype: str = "float64", seed: int = 0,
         angles: int = 0) -> Model: ...
def Baseline(dim: int, hidden: int | tuple[int, ...] | list[int] = (200, 200),
             activation: str = "tanh", *, dtype: str = "float64", seed: int = 0,
             angles: int = 0) -> Model: ...
def LNN(dim: int, hidden: int | tuple[int, ...] | list[int] = (200, 200),
        activation: str = "tanh", *, dtype: str = "float64", seed: int = 0, angles: int = 0,
        kinetic_prior: float = 1.0) -> Model: ...
def load(path: str | PathLike[str], *, angles: int = 0, kinetic_prior: float = 1.0) -> Model: ...
