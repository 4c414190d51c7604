# ch08_efficiency.gp -- chapter 08: efficiency 1 / (variance x time) of each
# estimator at N = 2^12, relative to independent uniform sampling of the same
# integral (bars, log scale). A bar at 100 means the same error in 1/100 of
# the time. The cosine-weighted estimator of the integral of cos has zero
# variance: its bar is cut off and labelled.
#
#   gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch08_efficiency.gp
#
# Reads data_dir/ch08_efficiency.csv; writes plot_dir/ch08_efficiency.png and .svg.

if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch08_efficiency.csv"
set datafile separator comma

# Bars grouped by integral (column 3), offset by estimator.
slot(e) = e eq "uniform" ? 0 : e eq "jittered" ? 1 : e eq "importance" ? 2 : 3
xpos(row) = column(3) * 5 + slot(strcol(2))
cap = 1e9
is(e) = strcol(2) eq e
shown(v) = v > cap ? cap : v
text(v) = v > cap ? "zero variance" : v >= 100 ? sprintf("%.2g", v) : sprintf("%.3g", v)

do for [term = 1:2] {
    if (term == 1) {
        set terminal pngcairo size 900,600 font ",10"
        set output plot_dir."/ch08_efficiency.png"
    } else {
        set terminal svg size 900,600 font ",10"
        set output plot_dir."/ch08_efficiency.svg"
    }
    set title "Efficiency 1/(variance × CPU time) at N = 2^{12}, relative to independent uniform sampling"
    set logscale y
    set yrange [0.3:cap * 30]
    set format y "10^{%L}"
    set ylabel "efficiency relative to independent uniform (log scale)"
    set xrange [-1:19]
    set xtics ("x^2 on [0,1]" 1.5, "cos θ, hemisphere" 6.5, "Gaussian, [0,1]^2" 11.5, "disk indicator" 16.5) scale 0
    set grid ytics lc rgb "#dddddd"
    set style fill solid 0.85 border -1
    set boxwidth 0.8
    set key top right font ",9"
    plot file skip 1 using (is("uniform") ? xpos(0) : NaN):(shown($8)) w boxes lc rgb "#1f77b4" t "independent uniform", \
         '' skip 1 using (is("jittered") ? xpos(0) : NaN):(shown($8)) w boxes lc rgb "#ff7f0e" t "jittered", \
         '' skip 1 using (is("importance") ? xpos(0) : NaN):(shown($8)) w boxes lc rgb "#2ca02c" t "importance (table; cosine-weighted on the hemisphere)", \
         '' skip 1 using (is("sobol_owen") ? xpos(0) : NaN):(shown($8)) w boxes lc rgb "#d62728" t "Owen-scrambled Sobol", \
         '' skip 1 using (xpos(0)):(shown($8) * 1.7):(text($8)) w labels font ",8" notitle
}
