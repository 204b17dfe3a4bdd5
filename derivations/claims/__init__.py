"""The paper's claims, one module each, grouped by section."""
