"""The language server (``plcbuilder lsp``): the PLC language for editors that
speak the Language Server Protocol. ``server`` puts it together, ``transport``
reads the messages (stdio, or a session per TCP connection), ``protocol``
holds them to JSON-RPC's and LSP's rules, ``checks`` compiles on a worker
thread, ``analysis`` checks documents, ``features`` answers the questions,
``access`` says which files may be read, ``projects`` finds a file's project,
``positions`` converts columns."""
