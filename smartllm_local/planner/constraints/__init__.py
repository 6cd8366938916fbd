"""The stages' constraints: what a plan (decomposition or free allocation), a restated allocation
and a coalition may say next, given the skills, the team's feasibility and the world check."""
