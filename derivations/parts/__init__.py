"""One module per part of the paper.  Each defines ``CLAIMS`` (a list of
:class:`derivations.registry.Claim`) and may define ``emit()`` returning
``(target, kernels)``: the kernels are written to ``symrb/_generated/<target>.py``.
Modules are discovered automatically (sorted by name); a leading underscore hides a module.
"""
