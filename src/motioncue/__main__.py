import signal

from motioncue.cli import main

status = main()
# Past this point the platform is parked: a late Ctrl-C or SIGTERM must not turn a clean exit
# into a death by signal (or a traceback) while the interpreter shuts down.
signal.pthread_sigmask(
    signal.SIG_BLOCK,
    [getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT") if hasattr(signal, n)],
)
raise SystemExit(status)
