"""The built-in problems, shipped unchanged from the canonical benchmark set.

Each ``NAME.json`` here is addressable by ``nbst.load_problem("NAME")``.
"""
