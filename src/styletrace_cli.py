"""Console entry point of the `styletrace` command.

`import styletrace` chooses the JIT backend, and can fail there (no usable libLLVM). That happens
before `styletrace.cli.main` could catch anything, so this module imports it and turns that failure into
the command line's one-line error and exit status 2.
"""
import sys


def main() -> int:
    try:
        from styletrace.cli import main as run
    except Exception as exc:  # styletrace.jit.BackendError; its module cannot be imported without the package
        if type(exc).__name__ == "BackendError":
            print(f"styletrace: error: {exc}", file=sys.stderr)
            return 2
        raise
    return run()


if __name__ == "__main__":
    sys.exit(main())
