"""The wheel ships ``symrb`` only.

``derivations`` (SymPy, development time) is importable in an editable install from a source
checkout (``pip install -e '.[derive]'``), but a built wheel leaves it out: ``build_py`` drops it
unless it runs for an editable install.  Everything else is configured in ``pyproject.toml``.
"""

from setuptools import setup
from setuptools.command.build_py import build_py


class build_py_symrb_only(build_py):
    def run(self) -> None:
        if not getattr(self, "editable_mode", False):
            self.packages = [p for p in self.packages if p.split(".")[0] != "derivations"]
        super().run()


setup(cmdclass={"build_py": build_py_symrb_only})
