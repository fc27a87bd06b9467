"""Merge controllers: the interface, key vehicles, HCOMC and its building blocks."""
