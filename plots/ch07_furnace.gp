# ch07_furnace.gp -- the closed furnace: L = E + K E + K^2 E + ... bounce by bounce.
# Data: ch07_furnace.csv from build/bin/07-radiometry --data DIR.
# Run: gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch07_furnace.gp
if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch07_furnace.csv"
set datafile separator ","

# The albedo the program was run with (column main = 1).
stats file using ($8 == 1 ? $1 : 1/0) skip 1 nooutput
rho = STATS_max
limit = 1.0 / (1.0 - rho)

do for [format in "png svg"] {
    if (format eq "png") { set terminal pngcairo size 900,600 font ",10" } else { set terminal svg size 900,600 font ",10" }
    set output plot_dir."/ch07_furnace.".format
    set multiplot layout 1,2 title sprintf("Closed furnace, Le = 1: radiance after k bounces converges to Le / (1 - rho)")

    set title sprintf("rho = %g: partial sums and the limit %g", rho, limit)
    set xlabel "bounces k"
    set ylabel "radiance L_k  (W m^{-2} sr^{-1}, Le = 1)"
    set xrange [-0.5:30.5]
    set yrange [0:limit * 1.1]
    set key right center box opaque
    set grid
    plot file skip 1 using ($8 == 1 ? $2 : 1/0):3 with impulses lw 6 lc rgb "#9ecae1" title "bounce k adds Le rho^k", \
         limit with lines lw 2 dt 2 lc rgb "#d62728" title "limit Le / (1 - rho)", \
         file skip 1 using ($8 == 1 ? $2 : 1/0):4 with linespoints pt 7 ps 0.8 lc rgb "#08519c" title "partial sum E + KE + ... + K^kE", \
         file skip 1 using ($8 == 1 ? $2 : 1/0):5 with points pt 6 ps 1.6 lc rgb "#ff7f0e" title "L_{k+1} = E + K L_k on 512 patches", \
         file skip 1 using ($8 == 1 ? $2 : 1/0):6 with points pt 2 ps 1.2 lc rgb "#2ca02c" title "L_{k+1} = E + K L_k, K by quadrature"

    set title "distance to the limit: rho^{k+1} / (1 - rho)"
    set ylabel "limit - L_k"
    set xrange [0:60]
    set yrange [1e-18:30]
    set logscale y
    set format y "10^{%T}"
    set key bottom left box opaque
    plot file skip 1 using ($1 == 0.5 ? $2 : 1/0):($7 - $4) with linespoints pt 7 ps 0.5 lc rgb "#1b9e77" title "rho = 0.5", \
         file skip 1 using ($8 == 1 && $1 != 0.5 && $1 != 0.95 ? $2 : 1/0):($7 - $4) with linespoints pt 7 ps 0.5 lc rgb "#08519c" title sprintf("rho = %g", rho), \
         file skip 1 using ($1 == 0.95 ? $2 : 1/0):($7 - $4) with linespoints pt 7 ps 0.5 lc rgb "#d95f02" title "rho = 0.95", \
         file skip 1 using ($1 == 0.5 ? $2 : 1/0):($1**($2+1) / (1 - $1)) with lines dt 2 lc rgb "black" title "rho^{k+1} / (1 - rho)", \
         file skip 1 using ($8 == 1 ? $2 : 1/0):($1**($2+1) / (1 - $1)) with lines dt 2 lc rgb "black" notitle, \
         file skip 1 using ($1 == 0.95 ? $2 : 1/0):($1**($2+1) / (1 - $1)) with lines dt 2 lc rgb "black" notitle
    unset logscale y
    set format y "%g"
    unset multiplot
    unset output
}
