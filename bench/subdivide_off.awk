# Midpoint subdivision of a triangle OFF file (every triangle into four, no smoothing), used by
# bench/dense-meshes.sh to make meshes of about a million triangles from the CGAL data:
#   awk -f bench/subdivide_off.awk -v rounds=2 bunny00.off > bunny1m.off
# Reads the plain OFF layout of the CGAL files ("OFF", counts, vertices, "3 a b c" faces).
{
    sub(/#.*/, "")
    for (i = 1; i <= NF; ++i) tok[++n] = $i
}
END {
    k = 1
    if (tok[k] == "OFF") ++k
    nv = tok[k++]; nf = tok[k++]; k++
    for (v = 0; v < nv; ++v) { x[v] = tok[k++]; y[v] = tok[k++]; z[v] = tok[k++] }
    for (f = 0; f < nf; ++f) {
        if (tok[k] != 3) { print "subdivide_off.awk: face " f " is not a triangle" > "/dev/stderr"; exit 1 }
        a[f] = tok[k + 1]; b[f] = tok[k + 2]; c[f] = tok[k + 3]; k += 4
    }
    if (rounds == "") rounds = 1
    for (r = 0; r < rounds; ++r) {
        split("", mid)
        m = 0
        for (f = 0; f < nf; ++f) {
            ab = midpoint(a[f], b[f]); bc = midpoint(b[f], c[f]); ca = midpoint(c[f], a[f])
            na[m] = a[f]; nb[m] = ab; nc[m++] = ca
            na[m] = ab; nb[m] = b[f]; nc[m++] = bc
            na[m] = ca; nb[m] = bc; nc[m++] = c[f]
            na[m] = ab; nb[m] = bc; nc[m++] = ca
        }
        nf = m
        for (f = 0; f < nf; ++f) { a[f] = na[f]; b[f] = nb[f]; c[f] = nc[f] }
    }
    print "OFF"
    print nv, nf, 0
    for (v = 0; v < nv; ++v) printf "%.9g %.9g %.9g\n", x[v], y[v], z[v]
    for (f = 0; f < nf; ++f) print 3, a[f], b[f], c[f]
}
function midpoint(p, q,    key) {
    key = p < q ? p "," q : q "," p
    if (!(key in mid)) {
        mid[key] = nv
        x[nv] = (x[p] + x[q]) / 2; y[nv] = (y[p] + y[q]) / 2; z[nv] = (z[p] + z[q]) / 2
        ++nv
    }
    return mid[key]
}
