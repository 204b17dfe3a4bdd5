"""Derivations of the paper's statements with SymPy (development time only; not in the wheel).

* :mod:`derivations.vocabulary`: symbols and shapes (``n``, ``matrix``, ``Lam``, ``W``) and the
  :class:`~derivations.vocabulary.Kernel` declaration;
* :mod:`derivations.symbolic`: the algebra the evidence works in (explicit matrices, noncommutative
  words, trace words) and the LaTeX of displayed formulas;
* :mod:`derivations.registry`: the claim registry (IDs D1-D12, S1-S15 of CLAIMS.md, and the
  checks M1.. of symrb's own methods), discovery of claims and kernels;
* :mod:`derivations.printer`: CSE and the NumPy printer that emits ``symrb/_generated``;
* :mod:`derivations.text` and :mod:`derivations.report`: claims as terminal text and as book
  tables; :mod:`derivations.cli`: the commands ``claims``, ``show``, ``verify``, ``derive``;
* :mod:`derivations.reference`: independent float64 / high-precision references (never symrb);
* :mod:`derivations.claims`: one module per claim, by section (``section2.d10_moser_veselov``
  is D10, ``section3.s02_rigid_body_equations`` is S2); code shared by a section's claims sits
  in its underscore modules;
* :mod:`derivations.methods`: checks of symrb's own methods (ids M1, ...), apart from the
  paper's claims (``cayley_step`` is M1).

Imports run one way: vocabulary <- symbolic <- registry <- printer <- text, report <- cli.

How a claim is written (``derivations/claims/section3/s02_rigid_body_equations.py`` is a model):

1. **Declare a claim above its evidence** with :func:`~derivations.registry.claim`; register its
   evidence with the decorator ``@S2.check(level, tol=..., form=...)``.  The first paragraph of the
   evidence function's docstring is its description (each check is described once).
2. **Formulas shown are formulas checked.**  ``[[key]]`` in a claim's ``statement``, ``printed`` or
   ``corrected`` text is the LaTeX of ``S2.formula(key, expr)``; the evidence evaluates that same
   ``expr`` (``S2.formulas[key]`` or the module-level name it was bound to).  Hand-written ``$...$``
   math may name objects but not state a relation (``=``, ``<``, ``\\le``, ...), except a parameter
   value such as ``$n=3$``.
3. **Emit what was verified.**  A :class:`~derivations.vocabulary.Kernel` holds the expressions of a
   generated function (``target`` = the generated module's name); evidence reads them with
   ``KERNEL["output"]`` (this records that the claim checked the kernel) and evaluates them with
   :func:`~derivations.symbolic.explicit` (fixed n) or :class:`~derivations.symbolic.Words`
   (every n).  Never type a kernel's formula a second time in an evidence function.
4. **Evidence that can fail for a wrong implementation.**  A float64 or high-precision check calls
   a public ``symrb`` function (imported inside the function: no module-level ``symrb`` import
   anywhere in ``derivations``) and compares it with an independent route
   (:mod:`derivations.reference`, an exact solution, a higher-precision run); tolerances are
   absolute or relative to a stated reference size, never to a spread the code under test
   computes.  Properties every flow of the class has (skewness, isospectrality, orthogonality)
   are tests, not evidence.
5. **A printed-form check fails for the reason it names**: it computes its residual the same way
   as its corrected twin (one function with a parameter), never a constant from a flag or an
   exception handler.

``python -m derivations derive`` writes ``symrb/_generated`` (``--check`` only compares);
``python -m derivations verify`` runs every claim's evidence.
"""
