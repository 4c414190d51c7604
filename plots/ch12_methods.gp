# Which method for which scene: relMSE against CPU seconds for the three
# unbiased methods -- chapter 09's path tracer (MIS, Russian roulette on
# throughput), chapter 11's bidirectional path tracer, chapter 12's
# Metropolis light transport (PSSMLT) -- on three scenes, each against one
# path-traced reference (128x128). A method keeps its colour in every panel.
# Data: build/bin/12-metropolis --data DIR  ->  DIR/ch12_methods_{cornell,ceiling-lamp,lamp}.csv
set datafile separator ","
array scenes[3] = ["cornell", "ceiling-lamp", "lamp"]
array titles[3] = ["Cornell box: light seen directly", \
                   "ceiling lamp (ch11): lit through the ceiling's bright patch", \
                   "lamp in a housing (ch12): light through a 2 cm channel"]
array methods[3] = ["path tracing (ch09, MIS)", "bidirectional (ch11)", "Metropolis (ch12, PSSMLT)"]
array colours[3] = ["#1f77b4", "#d62728", "#2ca02c"]
do for [format in "png svg"] {
    if (format eq "png") { set terminal pngcairo size 1500,480 font ",10" } else { set terminal svg size 1500,480 }
    set output plot_dir."/ch12_methods.".format
    set multiplot layout 1,3 title "Which method for which scene: error against CPU seconds (lower is better)"
    set logscale xy
    set grid
    set key bottom left
    set format y "10^{%L}"
    set xlabel "CPU seconds (2 threads together)"
    set ylabel "relMSE against the reference"
    do for [k=1:3] {
        set title titles[k]
        file = data_dir."/ch12_methods_".scenes[k].".csv"
        plot for [m=0:2] file using (column(1)==m ? $4 : 1/0):5 with linespoints lw 2 pt 7 \
             lc rgb colours[m+1] title methods[m+1]
    }
    unset multiplot
}
