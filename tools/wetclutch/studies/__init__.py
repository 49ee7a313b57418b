"""Studies across many simulated plants: film_study (``wetclutch film-study``), does the squeeze-film state
identified on two engagements generalise over a family of bench plants (issue 12)."""
