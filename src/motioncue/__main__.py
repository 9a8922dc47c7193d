from motioncue.cli import main

raise SystemExit(main())
