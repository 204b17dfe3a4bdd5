"""Code only the book needs: the computations of its pages that are not scenes.

* :mod:`symrb_book.discrete`: the conventions page and the Section 2 pages;
* :mod:`symrb_book.smooth`: the Section 3 pages;
* :mod:`symrb_book.style`: one colour, marker and line style per method, for every figure;
* :mod:`symrb_book.accuracy`: the work-precision panels and look-ups of the accuracy pages.
* :mod:`symrb_book.learning`: the training curves and times of the learning pages.

The package lives beside the pages (``book/lib``) and is not part of the ``symrb`` wheel.  The book
build puts ``book/lib`` on the notebook kernels' ``PYTHONPATH`` (``tools/_common.sh``,
``tools/run_page.py``) and pytest on its ``sys.path`` (``pythonpath`` in ``pyproject.toml``).
"""
