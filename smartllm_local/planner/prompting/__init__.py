"""What a stage shows the model: the prompts (skills, scene, team, worked examples), the scene's
objects they list, the chat template they are wrapped in, and the check that the examples are plans
the stage's own constraint would accept."""
