# The ray-count explosion at equal time: RMSE against a converged reference
# for N rays per bounce (N_light = N_glossy = N) at 1, 2, 4, ... samples per
# pixel, against CPU seconds. N = 1 is "more samples per pixel, one ray per
# bounce": the path tracer's choice.
# Data: build/bin/10-distribution --data DIR  ->  DIR/ch10_noise.csv
set datafile separator ","
file = data_dir."/ch10_noise.csv"
do for [fmt in "png svg"] {
    if (fmt eq "png") { set terminal pngcairo size 1000,450 font ",10" } else { set terminal svg size 1000,450 }
    set output plot_dir."/ch10_noise.".fmt
    set multiplot layout 1,2 title "Distribution ray tracing: N rays per bounce against N x the samples per pixel"
    set logscale xy
    set grid
    set key bottom left
    set ylabel "RMSE against the reference"
    set xlabel "samples per pixel"
    plot for [n in "1 2 4 8"] file using (column(1)==n+0 ? $2 : 1/0):4 every ::1 with linespoints lw 2 pt 7 title "N = ".n
    set xlabel "CPU seconds (all threads together)"
    plot for [n in "1 2 4 8"] file using (column(1)==n+0 ? $3 : 1/0):4 every ::1 with linespoints lw 2 pt 7 title "N = ".n
    unset multiplot
}
