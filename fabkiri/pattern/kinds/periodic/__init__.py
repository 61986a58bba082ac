"""Periodic quad sheets: the flat pattern a tube is rolled from."""
