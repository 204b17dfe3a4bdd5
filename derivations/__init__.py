"""Derivations of the paper's statements with SymPy (development time only).

* :mod:`derivations.registry`: the claim registry (IDs D1-D12, S1-S15 of CLAIMS.md);
* :mod:`derivations.codegen`: the printer and writer that emit ``symrb/_generated``;
* :mod:`derivations.parts`: one module per part of the paper; each defines ``CLAIMS`` and may
  define ``emit()`` returning ``(target_module_name, [Kernel, ...])``.
"""
