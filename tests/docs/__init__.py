"""Tests of the documentation that runs: the derivation notebook."""
