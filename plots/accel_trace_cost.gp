# accel_trace_cost.gp -- chapters 03-06: what one ray costs as the mesh grows.
# Time per ray (nanoseconds, one thread, closest hit) against the number of
# triangles of the tori field, log-log, one line per structure and Embree
# beside them. Brute force grows like N (slope 1), and so does flat (the
# same, eight triangles per AVX instruction: the Cornell box's choice); a
# good hierarchy like
# log N (a line that barely rises); the gap to Embree is what SIMD and
# decades of tuning buy. The wide BVH with streams (the same tree, 16 rays taking
# turns so their waits for memory overlap) shows how much of the rise at
# large N is waiting for memory.
#
#   make bench && gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/accel_trace_cost.gp
#
# Reads data_dir/accel.csv (written by tests/bench_accel.c); writes
# plot_dir/accel_trace_cost.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/accel.csv"
set datafile separator comma
# ns per ray of structure s from a Mrays/s column; NaN for other rows
ns(s, col) = (strcol(1) eq s && column(col) > 0) ? 1000.0 / column(col) : NaN

rows(s) = sprintf("< grep '^%s,' '%s'", s, file)

names = "brute flat grid kdtree bvh-median bvh-sah wide-bvh-sah wide-bvh-stream embree"
titles = "brute-force flat(8/AVX) grid kd-tree BVH(median) BVH(SAH) wide-BVH(SAH) wide-BVH(streams) Embree"
set style line 1 lc rgb "#7f7f7f" lw 2 pt 7 ps 0.7
set style line 2 lc rgb "#7f7f7f" lw 2 dt (2,2) pt 6 ps 0.7
set style line 3 lc rgb "#2ca02c" lw 2 pt 5 ps 0.7
set style line 4 lc rgb "#ff7f0e" lw 2 pt 9 ps 0.8
set style line 5 lc rgb "#9467bd" lw 2 pt 11 ps 0.8
set style line 6 lc rgb "#1f77b4" lw 2 pt 13 ps 0.8
set style line 7 lc rgb "#17becf" lw 2 pt 15 ps 0.8
set style line 8 lc rgb "#17becf" lw 2 dt (2,2) pt 4 ps 0.8
set style line 9 lc rgb "#d62728" lw 2 dt (6,3) pt 3 ps 0.8

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 1000,450 font ",9"
        set output plot_dir."/accel_trace_cost.png"
    } else {
        set terminal svg size 1000,450 font ",9"
        set output plot_dir."/accel_trace_cost.svg"
    }
    set multiplot layout 1,2 title "Time per ray against mesh size (tori field, closest hit, 1 thread; lower is better)"
    set logscale xy
    set format x "10^{%L}"
    set grid xtics ytics mxtics mytics lc rgb "#dddddd"
    set xlabel "triangles"
    set ylabel "nanoseconds per ray"
    set key top left font ",8" noopaque
    do for [panel = 1:2] {
        col = panel == 1 ? 9 : 11
        set title (panel == 1 ? "coherent rays (camera-like)" : "incoherent rays (random directions)")
        # one structure's rows are not contiguous in the CSV (it is ordered by
        # size), and gnuplot breaks a line at every skipped row: grep them out
        plot for [k = 1:words(names)] rows(word(names, k)) using 2:(ns(word(names, k), col)) w lp ls k t word(titles, k)
    }
    unset multiplot
}
