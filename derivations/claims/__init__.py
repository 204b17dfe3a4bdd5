"""The paper's claims, one module per claim, grouped by section (``section2``, ``section3``)."""
