"""The facade: plain functions that compose the pipeline.

    compile_source / compile_file   source -> diagnostics + Program
    run (plcbuilder.simulate)       Program(s) -> simulated controller run
    build_project (plcbuilder.project.build)

Options are passed in; nothing here keeps global state.
"""
