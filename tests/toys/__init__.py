"""Toy extensions registered from outside the package (registry calls only)."""
