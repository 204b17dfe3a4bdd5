"""Checks of symrb's own methods (ids M1, M2, ...), apart from the paper's claims."""
