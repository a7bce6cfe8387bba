"""Reasons the IDE's side of the link gives for a disconnect that are its own
doing, shared by the connection and the panels that report disconnects."""

#: :meth:`ControllerConnection.shutdown`: the IDE closed the connection itself
#: (another project, quitting), which is not an error
CLOSED_BY_IDE = "closed by the IDE"
