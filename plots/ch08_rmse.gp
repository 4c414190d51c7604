# ch08_rmse.gp -- chapter 08: RMSE of each estimator against the sample
# count N, log-log, one panel per integral, with reference slopes.
#
#   gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch08_rmse.gp
#
# Reads data_dir/ch08_convergence.csv (build/bin/08-monte-carlo --data DIR);
# writes plot_dir/ch08_rmse.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch08_convergence.csv"
set datafile separator comma

# One curve: the rows of one integral and one estimator (others are NaN).
pick(i, e, col) = (strcol(1) eq i && strcol(2) eq e) ? column(col) : NaN

# Reference lines C * N^slope through the independent estimator's RMSE at N = 1.
array A[4]
names = "x2 hemisphere_cos gaussian disk"
do for [k = 1:4] {
    stats file skip 1 using (pick(word(names, k), "uniform", 7) * (column(3) == 0 ? 1 : NaN)) nooutput
    A[k] = STATS_max
}

set style line 1 lc rgb "#1f77b4" lw 2 pt 7 ps 0.6
set style line 2 lc rgb "#ff7f0e" lw 2 pt 5 ps 0.6
set style line 3 lc rgb "#2ca02c" lw 2 pt 9 ps 0.7
set style line 4 lc rgb "#d62728" lw 2 dt (6,3) pt 13 ps 0.7
set style line 9 lc rgb "#888888" lw 1 dt 2
set style line 10 lc rgb "#888888" lw 1 dt 4
set style line 11 lc rgb "#888888" lw 1 dt 3

panel_title(k) = k == 1 ? "x^2 on [0,1] (1D)" : k == 2 ? "cos θ over the hemisphere" : \
                 k == 3 ? "Gaussian σ = 1/4 on [0,1]^2 (smooth)" : "disk indicator r = 0.4 (discontinuous)"
importance_title(k) = k == 2 ? "cosine-weighted (p ∝ f)" : k == 4 ? "" : "importance (16-bin table)"

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 900,600 font ",9"
        set output plot_dir."/ch08_rmse.png"
    } else {
        set terminal svg size 900,600 font ",9"
        set output plot_dir."/ch08_rmse.svg"
    }
    set multiplot layout 2,2 title "Monte Carlo: RMSE against sample count N"
    set logscale x 2
    set logscale y 10
    set xtics 16
    set format x "2^{%L}"
    set format y "10^{%L}"
    set xrange [1:65536]
    set yrange [1e-10:10]
    set grid xtics ytics mxtics mytics lc rgb "#dddddd"
    set xlabel "samples per estimate N"
    set ylabel "RMSE (same units as the integral)"
    set key bottom left font ",8" spacing 0.9 noopaque
    do for [k = 1:4] {
        set title panel_title(k)
        i = word(names, k)
        a = A[k]
        # The reference lines are labelled where they leave the panel.
        unset label
        set label 1 "N^{-1/2}" at 20000, a * 20000**-0.5 * 3 font ",8" tc rgb "#666666"
        set label 2 "N^{-1}" at 20000, a * 20000**-1 * 3 font ",8" tc rgb "#666666"
        set label 3 "N^{-3/2}" at 20000, a * 20000**-1.5 * 3 font ",8" tc rgb "#666666"
        if (k == 4) {
            plot file skip 1 using (pick(i, "uniform", 4)):(pick(i, "uniform", 7)) w lp ls 1 t "independent uniform", \
                 '' skip 1 using (pick(i, "jittered", 4)):(pick(i, "jittered", 7)) w lp ls 2 t "jittered", \
                 '' skip 1 using (pick(i, "sobol_owen", 4)):(pick(i, "sobol_owen", 7)) w lp ls 4 t "Owen-scrambled Sobol", \
                 a * x**-0.5 w l ls 9 notitle, a * x**-1 w l ls 10 notitle, a * x**-1.5 w l ls 11 notitle
        } else {
            plot file skip 1 using (pick(i, "uniform", 4)):(pick(i, "uniform", 7)) w lp ls 1 t "independent uniform", \
                 '' skip 1 using (pick(i, "jittered", 4)):(pick(i, "jittered", 7)) w lp ls 2 t "jittered", \
                 '' skip 1 using (pick(i, "importance", 4)):(pick(i, "importance", 7)) w lp ls 3 t importance_title(k), \
                 '' skip 1 using (pick(i, "sobol_owen", 4)):(pick(i, "sobol_owen", 7)) w lp ls 4 t "Owen-scrambled Sobol", \
                 a * x**-0.5 w l ls 9 notitle, a * x**-1 w l ls 10 notitle, a * x**-1.5 w l ls 11 notitle
        }
    }
    unset multiplot
}
