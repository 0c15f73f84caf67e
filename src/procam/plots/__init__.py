"""Figures (the only package that imports matplotlib; always the Agg backend)."""
