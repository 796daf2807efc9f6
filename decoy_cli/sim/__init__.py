"""The headless simulator: round state, movement, line of sight and combat, bomb rules, env."""
