"""Third-party code kept verbatim inside mvtrack, each with its licence; see each package."""
