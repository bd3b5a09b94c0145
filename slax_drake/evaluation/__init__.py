"""Evaluation: the shelf-simulator Table I benchmark, the physics benchmark and the trial runner, behind one
``slax-drake benchmark`` command."""
