"""Simulation core: scenario, demand, engine and log."""
