"""The server backend (:mod:`.backend`) and what it speaks with: the connection, each server's
dialect, line requests, the slot mirror and the served model's vocabulary read on this side."""
