"""slax-drake: lateral-access mechanical search on shelves with the bluction tool (SLAX-RAY) on Drake."""

__version__ = "0.1.0"
