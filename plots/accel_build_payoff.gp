# accel_build_payoff.gp -- chapters 03-06: when does a better build pay for
# itself? Total time = build time + rays x time per ray, against the number
# of rays traced, for each structure on the largest tori field in the
# benchmark (closest hit, incoherent rays, one thread). A structure that is
# slow to build (the kd-tree, SAH) starts higher and wins once enough rays
# are traced; where two lines cross is the number of rays at which the
# better tree has paid for its build. Drawn relative to the lecture's BVH
# (median split), so that below 1 means "cheaper in total than the
# lecture's BVH for this many rays".
#
#   make bench && gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/accel_build_payoff.gp
#
# Reads data_dir/accel.csv (tests/bench_accel.c); writes
# plot_dir/accel_build_payoff.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/accel.csv"
set datafile separator comma

stats file skip 1 using 2 nooutput
N = int(STATS_max)
rows(s) = sprintf("< grep '^%s,%d,' '%s'", s, N, file)

names = "grid kdtree bvh-median bvh-sah wide-bvh-sah embree"
titles = "grid kd-tree BVH(median) BVH(SAH) wide-BVH(SAH) Embree"
array build_ms[words(names)]
array ns_per_ray[words(names)]
do for [k = 1:words(names)] {
    build_ms[k] = NaN
    ns_per_ray[k] = NaN
    if (system(sprintf("grep -c '^%s,%d,' '%s' || true", word(names, k), N, file)) + 0 > 0) {
        stats rows(word(names, k)) using 3 nooutput
        build_ms[k] = STATS_max
        stats rows(word(names, k)) using (1000.0 / $11) nooutput
        ns_per_ray[k] = STATS_max
    }
}
# total milliseconds for r rays, and as a fraction of the lecture's BVH
# (median split: the cheapest hierarchy to build)
total(k, r) = build_ms[k] + r * ns_per_ray[k] * 1e-6
reference = 3
relative(k, r) = total(k, r) / total(reference, r)
present(k) = build_ms[k] == build_ms[k]

set style line 1 lc rgb "#2ca02c" lw 2
set style line 2 lc rgb "#ff7f0e" lw 2
set style line 3 lc rgb "#9467bd" lw 2
set style line 4 lc rgb "#1f77b4" lw 2
set style line 5 lc rgb "#17becf" lw 2
set style line 6 lc rgb "#d62728" lw 2 dt (6,3)

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 800,520 font ",9"
        set output plot_dir."/accel_build_payoff.png"
    } else {
        set terminal svg size 800,520 font ",9"
        set output plot_dir."/accel_build_payoff.svg"
    }
    set title sprintf("Build + trace: total time for %d triangles (incoherent closest hit, 1 thread)", N)
    set logscale x
    set yrange [0:3]
    set format x "10^{%L}"
    set xrange [1e3:1e9]
    set samples 200
    set grid xtics ytics lc rgb "#dddddd"
    set xlabel "rays traced"
    set ylabel "(build + trace time) / that of BVH(median)"
    set key top right font ",8" noopaque
    plot for [k = 1:words(names)] (present(k) ? relative(k, x) : NaN) w l ls k \
         t (present(k) ? sprintf("%s: build %.0f ms, %.0f ns/ray", word(titles, k), build_ms[k], ns_per_ray[k]) : "")
}
