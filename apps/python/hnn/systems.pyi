# Types of hnn.systems (systems.py), for editors; tests/python/hnn_test.py checks that it names
# every name of __all__.
from typing import Optional, Sequence

from ._hnn import _systems

System = _systems.System

__all__: list[str]

def Spring(stiffness: float = 1.0, kinetic: float = 1.0) -> System: ...
def Pendulum(potential: float = 3.0, kinetic: float = 1.0) -> System: ...
def NBody(n: int = 2, masses: Optional[Sequence[float]] = None,
          gravity: float = 1.0) -> System: ...
def DoublePendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                   g: float = 9.81) -> System: ...
def Expression(hamiltonian: str, coords: Sequence[str], momenta: Sequence[str]) -> System: ...
