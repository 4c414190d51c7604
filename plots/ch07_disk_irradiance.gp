# ch07_disk_irradiance.gp -- irradiance on the axis of a disk light against height:
# both numeric forms (solid angle, area) against pi L R^2 / (R^2 + h^2), and the
# point-light approximation I / h^2 with I = pi R^2 L.
# Data: ch07_disk_irradiance.csv from build/bin/07-radiometry --data DIR.
# Run: gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch07_disk_irradiance.gp
if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch07_disk_irradiance.csv"
set datafile separator ","

do for [format in "png svg"] {
    if (format eq "png") { set terminal pngcairo size 900,600 font ",10" } else { set terminal svg size 900,600 font ",10" }
    set output plot_dir."/ch07_disk_irradiance.".format
    set title "Irradiance on the axis of a disk light (radius R = 1, radiance L = 1) at height h"
    set xlabel "height h / R"
    set ylabel "irradiance E  (W m^{-2}, L = 1 W m^{-2} sr^{-1})"
    set logscale xy
    set format x "10^{%T}"
    set format y "10^{%T}"
    set xrange [0.03:100]
    set yrange [1e-4:20]
    set grid
    set key bottom left box opaque
    plot pi with lines dt 3 lw 2 lc rgb "#7f7f7f" title "pi L: the whole hemisphere (h -> 0)", \
         file skip 1 using 1:5 with lines dt 2 lw 2 lc rgb "#d62728" title "point light I / h^2, I = pi R^2 L", \
         file skip 1 using 1:4 with lines lw 2 lc rgb "#08519c" title "closed form pi L R^2 / (R^2 + h^2)", \
         file skip 1 using 1:2 with points pt 6 ps 1.4 lc rgb "#ff7f0e" title "numeric: integral of L cos theta d omega", \
         file skip 1 using 1:3 with points pt 2 ps 1.0 lc rgb "#2ca02c" title "numeric: integral of L cos theta cos theta' / r^2 dA"
    unset output
}
