#!/usr/bin/env python3
# User CPU seconds of each translation unit in a build folder's compile_commands.json, compiled one
# at a time:  bench/tu_cost.py build/compile_commands.json .
# (ccache bypassed, object to /dev/null); prints them sorted, with the total.
import json, subprocess, sys, resource, shlex, os
d = json.load(open(sys.argv[1]))
rows = []
for e in d:
    args = shlex.split(e['command'])
    if 'ccache' in args[0]: args = args[1:]
    if '-o' in args:
        i = args.index('-o'); args[i+1] = '/dev/null'
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    subprocess.run(args, cwd=e['directory'], check=True)
    rows.append((resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before, os.path.relpath(e['file'], sys.argv[2])))
rows.sort(reverse=True)
for t, f in rows: print(f'{t:7.1f} {f}')
print(f'{sum(t for t,_ in rows):7.1f} total ({len(rows)} files)')
