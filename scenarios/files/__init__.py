"""Files sewfmu writes and unpacks: atomic writes, an output folder's own files, the scratch left
by dead processes. The lowest wing: every other may use it, it uses none."""
