"""python -m voxfx ARGS: runs the voxfx command line that came with this package (the same
program as `voxfx` from a CMake install), replacing this process, so its exit status, output and
signals are the command's own."""
import os
import sys


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    cli = os.path.join(here, "voxfx-cli")
    if not os.access(cli, os.X_OK):
        sys.exit(f"voxfx: the command line program is not in this installation ({cli} is missing)")
    os.execv(cli, ["voxfx", *sys.argv[1:]])


if __name__ == "__main__":
    main()
