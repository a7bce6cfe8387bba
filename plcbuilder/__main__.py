from plcbuilder.cli.main import main

raise SystemExit(main())
