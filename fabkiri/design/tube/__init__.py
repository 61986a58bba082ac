"""Inverse design of tubes: periodic sheets whose closed states roll into cylinders."""
