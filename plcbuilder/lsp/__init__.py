"""The language server (``plcbuilder lsp``): the PLC language for editors that
speak the Language Server Protocol. ``server`` puts it together, ``transport``
reads the messages, ``analysis`` checks documents, ``features`` answers the
questions, ``projects`` finds a file's project, ``positions`` converts columns."""
