# ch08_cost.gp -- chapter 08: what accuracy costs. RMSE against the wall time
# of one estimate (points, warps and integrand, N = 1 .. 2^16 along each
# curve), one panel per integral. Lower and further left is better; a curve
# that starts higher but falls faster wins once enough time is spent.
#
#   gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch08_cost.gp
#
# Reads data_dir/ch08_convergence.csv; writes plot_dir/ch08_cost.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch08_convergence.csv"
set datafile separator comma
pick(i, e, col) = (strcol(1) eq i && strcol(2) eq e) ? column(col) : NaN
names = "x2 hemisphere_cos gaussian disk"

set style line 1 lc rgb "#1f77b4" lw 2 pt 7 ps 0.6
set style line 2 lc rgb "#ff7f0e" lw 2 pt 5 ps 0.6
set style line 3 lc rgb "#2ca02c" lw 2 pt 9 ps 0.7
set style line 4 lc rgb "#d62728" lw 2 dt (6,3) pt 13 ps 0.7

panel_title(k) = k == 1 ? "x^2 on [0,1] (1D)" : k == 2 ? "cos θ over the hemisphere" : \
                 k == 3 ? "Gaussian σ = 1/4 on [0,1]^2 (smooth)" : "disk indicator r = 0.4 (discontinuous)"
importance_title(k) = k == 2 ? "cosine-weighted (p ∝ f)" : "importance (16-bin table)"

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 900,600 font ",9"
        set output plot_dir."/ch08_cost.png"
    } else {
        set terminal svg size 900,600 font ",9"
        set output plot_dir."/ch08_cost.svg"
    }
    set multiplot layout 2,2 title "What accuracy costs: RMSE against CPU time per estimate (N = 1 .. 2^{16} along each curve)"
    set logscale xy
    set format x "10^{%L}"
    set format y "10^{%L}"
    set yrange [1e-10:10]
    set grid xtics ytics lc rgb "#dddddd"
    set xlabel "CPU time per estimate (seconds)"
    set ylabel "RMSE (same units as the integral)"
    set key bottom left font ",8" spacing 0.9 noopaque
    do for [k = 1:4] {
        set title panel_title(k)
        i = word(names, k)
        if (k == 4) {
            plot file skip 1 using (pick(i, "uniform", 9)):(pick(i, "uniform", 7)) w lp ls 1 t "independent uniform", \
                 '' skip 1 using (pick(i, "jittered", 9)):(pick(i, "jittered", 7)) w lp ls 2 t "jittered", \
                 '' skip 1 using (pick(i, "sobol_owen", 9)):(pick(i, "sobol_owen", 7)) w lp ls 4 t "Owen-scrambled Sobol"
        } else {
            plot file skip 1 using (pick(i, "uniform", 9)):(pick(i, "uniform", 7)) w lp ls 1 t "independent uniform", \
                 '' skip 1 using (pick(i, "jittered", 9)):(pick(i, "jittered", 7)) w lp ls 2 t "jittered", \
                 '' skip 1 using (pick(i, "importance", 9)):(pick(i, "importance", 7)) w lp ls 3 t importance_title(k), \
                 '' skip 1 using (pick(i, "sobol_owen", 9)):(pick(i, "sobol_owen", 7)) w lp ls 4 t "Owen-scrambled Sobol"
        }
    }
    unset multiplot
}
