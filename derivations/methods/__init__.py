"""Checks of symrb's own methods (ids M1..), apart from the paper's claims."""
