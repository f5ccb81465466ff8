"""Formulations: one per (model kind × data kind), each turning data into a problem to solve."""
