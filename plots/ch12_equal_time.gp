# Which method to pick: relMSE against the cached reference as a function of
# CPU seconds, for chapter 09's path tracer (MIS, Russian roulette on
# throughput) and Metropolis light transport (PSSMLT), on the Cornell box
# (path tracing wins) and on the lamp in a housing (Metropolis wins).
# Data: build/bin/12-metropolis --data DIR  ->  DIR/ch12_equal_time_{cornell,lamp}.csv
set datafile separator ","
set logscale xy
set grid
set key bottom left
set xlabel "CPU seconds (2 threads together)"
set ylabel "relMSE against the reference"
set format y "10^{%L}"
do for [fmt in "png svg"] {
    if (fmt eq "png") { set terminal pngcairo size 1000,450 font ",10" } else { set terminal svg size 1000,450 }
    set output plot_dir."/ch12_equal_time.".fmt
    set multiplot layout 1,2 title "Equal time: path tracing against Metropolis light transport"
    set title "Cornell box (light seen directly)"
    file = data_dir."/ch12_equal_time_cornell.csv"
    plot file using (column(1)==0 ? $5 : 1/0):7 with linespoints lw 2 pt 7 title "path tracing (MIS)", \
         file using (column(1)==1 ? $5 : 1/0):7 with linespoints lw 2 pt 7 title "Metropolis (PSSMLT)"
    set title "lamp in a housing (light only through a 2 cm channel)"
    file = data_dir."/ch12_equal_time_lamp.csv"
    plot file using (column(1)==0 ? $5 : 1/0):7 with linespoints lw 2 pt 7 title "path tracing (MIS)", \
         file using (column(1)==1 ? $5 : 1/0):7 with linespoints lw 2 pt 7 title "Metropolis (PSSMLT)"
    unset multiplot
}
