"""The browser explorer (`explorer serve`): viser shows the gear moving, with controls, plots and
read-outs. `model` holds everything that does not need viser; `app` wires it to a server."""
