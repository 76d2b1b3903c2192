"""sewfmu's host side, in wings by job (docs/architecture.md): internal; sewfmu's API is its
public face. Earlier releases had `sewfmu.scenarios()` for the catalogue's names, which made this
package's name a function; the function is `sewfmu.catalogue()` now, and the package answers the
old call for one more release, with a DeprecationWarning."""
import sys
import types
import warnings


class _Package(types.ModuleType):
    def __call__(self) -> list[str]:
        warnings.warn("sewfmu.scenarios() is now sewfmu.catalogue(); the old name goes in the next "
                      "release", DeprecationWarning, stacklevel=2)
        from sewfmu.scenarios.format.loader import catalogue  # the catalogue, only when asked

        return sorted(catalogue())


sys.modules[__name__].__class__ = _Package
