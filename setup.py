"""The wheel ships ``symrb`` only.

``derivations`` (SymPy, development time) and ``benchmarks`` (the harness behind ``symrb bench``)
are importable in an editable install from a source checkout (``pip install -e '.[derive]'``),
but a built wheel leaves them out: ``build_py`` drops them unless it runs for an editable
install.  Everything else is configured in ``pyproject.toml``.
"""

from setuptools import setup
from setuptools.command.build_py import build_py


class build_py_symrb_only(build_py):
    def run(self) -> None:
        if not getattr(self, "editable_mode", False):
            dev_only = ("derivations", "benchmarks")
            self.packages = [p for p in self.packages if p.split(".")[0] not in dev_only]
        super().run()


setup(cmdclass={"build_py": build_py_symrb_only})
