# Which method to pick: relMSE against CPU seconds for chapter 09's best path
# tracer (MIS, Russian roulette on throughput) and bidirectional path tracing,
# on the Cornell box (BDPT about even or slower) and the ceiling lamp (BDPT wins).
# Data: build/bin/11-bidirectional --data DIR  ->  DIR/ch11_equal_time_{cornell,ceiling-lamp}.csv
set datafile separator ","
titles = "path-tracing(ch09-MIS) bidirectional(MIS)"
do for [format in "png svg"] {
    if (format eq "png") { set terminal pngcairo size 1000,450 font ",10" } else { set terminal svg size 1000,450 }
    set output plot_dir."/ch11_equal_time.".format
    set multiplot layout 1,2 title "Equal time: error against CPU seconds"
    set logscale xy
    set grid
    set key bottom left
    set format y "10^{%L}"
    set xlabel "CPU seconds (2 threads together)"
    set ylabel "relMSE against the reference"
    do for [scene in "cornell ceiling-lamp"] {
        file = data_dir."/ch11_equal_time_".scene.".csv"
        set title scene
        plot for [k=0:1] file using (column(1)==k ? $4 : 1/0):5 with linespoints lw 2 pt 7 \
             title word(titles, k+1)
    }
    unset multiplot
}
