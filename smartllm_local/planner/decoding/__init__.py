"""How a stage's output is written under its constraint: the grammar data and its matcher, the line
protocol a constraint speaks (forced text or a choice of grammars), the line ends a token may run
past, and the writer that drives a model's tokens through it all."""
