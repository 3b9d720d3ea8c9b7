"""Data association: distances and gates (papers 1 and 2), and assignment rules."""
