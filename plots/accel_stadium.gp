# accel_stadium.gp -- chapter 04: the teapot in a stadium. Triangles tested
# and time per ray for a uniform grid as its cell density C grows, on the
# tori field (evenly spread triangles) and on the teapot in a stadium (a
# dense mesh in a huge empty scene), with the hierarchies of chapters 05-06
# as horizontal lines. On the tori field the grid is about as good as the
# trees; in the stadium it tests thousands of triangles per ray at the
# lecture's C = 27, and refining it buys little for a lot of memory, while
# the trees adapt to where the triangles are.
#
#   make bench && gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/accel_stadium.gp
#
# Reads data_dir/stadium.csv (bench_accel --stadium); writes
# plot_dir/accel_stadium.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/stadium.csv"
set datafile separator comma
rows(m, s) = sprintf("< grep '^%s,%s,' '%s'", m, s, file)

# the hierarchies' figures, as constants for horizontal lines
trees = "kdtree bvh-sah wide-bvh-sah"
tree_titles = "kd-tree BVH(SAH) wide-BVH(SAH)"
array tris[6]
array ns[6]
do for [m = 1:2] {
    do for [k = 1:words(trees)] {
        i = (m - 1) * 3 + k
        tris[i] = NaN
        ns[i] = NaN
        if (system(sprintf("grep -c '^%s,%s,' '%s' || true", m == 1 ? "tori" : "stadium", word(trees, k), file)) + 0 > 0) {
            stats rows(m == 1 ? "tori" : "stadium", word(trees, k)) using 8 nooutput
            tris[i] = STATS_max
            stats rows(m == 1 ? "tori" : "stadium", word(trees, k)) using (1000.0 / $9) nooutput
            ns[i] = STATS_max
        }
    }
}
present(i) = tris[i] == tris[i]

set style line 1 lc rgb "#2ca02c" lw 2 pt 5 ps 0.8
set style line 2 lc rgb "#d62728" lw 2 pt 7 ps 0.8
set style line 3 lc rgb "#ff7f0e" lw 1.5 dt (6,3)
set style line 4 lc rgb "#1f77b4" lw 1.5 dt (6,3)
set style line 5 lc rgb "#17becf" lw 1.5 dt (6,3)
set style line 6 lc rgb "#ff7f0e" lw 1.5 dt (2,2)
set style line 7 lc rgb "#1f77b4" lw 1.5 dt (2,2)
set style line 8 lc rgb "#17becf" lw 1.5 dt (2,2)

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 1000,450 font ",9"
        set output plot_dir."/accel_stadium.png"
    } else {
        set terminal svg size 1000,450 font ",9"
        set output plot_dir."/accel_stadium.svg"
    }
    set multiplot layout 1,2 title "The teapot in a stadium: a uniform grid against cell density C (rays aimed at random triangles, 1 thread)"
    set logscale xy
    set xrange [0.8:300]
    set grid xtics ytics lc rgb "#dddddd"
    set xlabel "grid density C (#cells = C x #triangles; the lecture's C = 27)"
    set key top right font ",8" noopaque
    set samples 2
    do for [panel = 1:2] {
        if (panel == 1) {
            set title "triangles tested per ray"
            set ylabel "triangles tested per ray"
            plot rows("tori", "grid") using 3:8 w lp ls 1 t "grid, tori field", \
                 rows("stadium", "grid") using 3:8 w lp ls 2 t "grid, teapot in stadium", \
                 for [k = 1:3] (present(k) ? tris[k] : NaN) w l ls 2 + k t (present(k) ? word(tree_titles, k)." (tori)" : ""), \
                 for [k = 1:3] (present(3 + k) ? tris[3 + k] : NaN) w l ls 5 + k t (present(3 + k) ? word(tree_titles, k)." (stadium)" : "")
        } else {
            set title "time per ray"
            set ylabel "nanoseconds per ray"
            plot rows("tori", "grid") using 3:(1000.0 / $9) w lp ls 1 t "grid, tori field", \
                 rows("stadium", "grid") using 3:(1000.0 / $9) w lp ls 2 t "grid, teapot in stadium", \
                 for [k = 1:3] (present(k) ? ns[k] : NaN) w l ls 2 + k t (present(k) ? word(tree_titles, k)." (tori)" : ""), \
                 for [k = 1:3] (present(3 + k) ? ns[3 + k] : NaN) w l ls 5 + k t (present(3 + k) ? word(tree_titles, k)." (stadium)" : "")
        }
    }
    unset multiplot
}
