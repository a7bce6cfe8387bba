"""The debug adapter (``plcbuilder dap``): the Debug Adapter Protocol bridged
to the controller's debugger over the link. ``session`` answers the requests,
``breakpoints`` turns the client's breakpoints into the debugger's, ``inspect``
shows the halted state as threads, frames, scopes and variables, ``wire``
reads and writes the frames."""
