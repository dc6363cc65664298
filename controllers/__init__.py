"""Force laws of the fork and tire, injected into MuJoCo through its control callback.

Installed as ``mtbmj.controllers``. Each law is a small immutable object; ``ForkLaw`` composes a
spring, a damper and a friction law; ``ForkCallback`` and ``installed`` put it into MuJoCo. Those
two are imported on first use (``__getattr__``): the laws need no MuJoCo, and a command line's
parsers that read a law module's constants (``mtbmj --help``) import none.
"""
from mtbmj.controllers.damper import BilinearDamper, DigressiveDamper, LinearDamper, OrificeDamper, TableDamper
from mtbmj.controllers.fork import ForkLaw
from mtbmj.controllers.friction import (Coulomb, CoulombViscous, LuGre, NoFriction, Stiction, Sticking, Stribeck,
                                       smooth_sign)
from mtbmj.controllers.stops import EndStops, Rim
from mtbmj.controllers.spring import (
    P_ATM, AirSpring, BilinearSpring, DirectionalSpring, LinearSpring, ProgressiveSpring, TopOutSpring,
)
from mtbmj.controllers.tire import ContactFloor, KelvinVoigt, TireLaw

__all__ = [
    "ForkCallback", "installed", "ForkLaw",
    "LinearSpring", "BilinearSpring", "ProgressiveSpring", "DirectionalSpring", "TopOutSpring", "AirSpring", "P_ATM",
    "LinearDamper", "BilinearDamper", "DigressiveDamper", "OrificeDamper", "TableDamper",
    "NoFriction", "Coulomb", "CoulombViscous", "Stiction", "Stribeck", "LuGre", "Sticking", "smooth_sign",
    "EndStops", "Rim",
    "ContactFloor", "KelvinVoigt", "TireLaw",
]


def __getattr__(name):
    if name in ("ForkCallback", "installed"):
        from mtbmj.controllers import callback

        return getattr(callback, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
