# What accuracy costs in time: relMSE of each rung of the path tracer against
# the cached reference, as a function of samples per pixel and of seconds.
# Data: build/bin/09-path-tracing --data DIR  ->  DIR/ch09_convergence_cornell.csv
set datafile separator ","
set terminal pngcairo size 1000,450 font ",10"
set output plot_dir."/ch09_error.png"
file = data_dir."/ch09_convergence_cornell.csv"
set multiplot layout 1,2 title "Path tracing the Cornell box: error against samples and against time"
set logscale xy
set grid
set key bottom left
set xlabel "samples per pixel"
set ylabel "relMSE against the reference"
set format y "10^{%L}"
# rows 0-3: the ladder with random numbers; 4 and 5: its first and last rung
# with Sobol samples (--sampler sobol), dashed, in the colour of their rung
titles = "lecture cosine MIS MIS+RR-throughput lecture+Sobol MIS+RR-throughput+Sobol"
rung_colour(k) = k == 4 ? 1 : k == 5 ? 4 : k + 1
plot for [k=0:3] file using (column(1)==k ? $4 : 1/0):7 with linespoints lw 2 pt 7 lc rung_colour(k) title word(titles, k+1), \
     for [k=4:5] file using (column(1)==k ? $4 : 1/0):7 with linespoints lw 2 dt 2 pt 6 lc rung_colour(k) title word(titles, k+1), \
     [1:256] 0.3/x with lines dt 3 lc "gray" title "slope -1"
set xlabel "CPU seconds (2 threads together)"
plot for [k=0:3] file using (column(1)==k ? $9 : 1/0):7 with linespoints lw 2 pt 7 lc rung_colour(k) title word(titles, k+1), \
     for [k=4:5] file using (column(1)==k ? $9 : 1/0):7 with linespoints lw 2 dt 2 pt 6 lc rung_colour(k) title word(titles, k+1)
unset multiplot
set terminal svg size 1000,450
set output plot_dir."/ch09_error.svg"
set multiplot layout 1,2 title "Path tracing the Cornell box: error against samples and against time"
set xlabel "samples per pixel"
plot for [k=0:3] file using (column(1)==k ? $4 : 1/0):7 with linespoints lw 2 pt 7 lc rung_colour(k) title word(titles, k+1), \
     for [k=4:5] file using (column(1)==k ? $4 : 1/0):7 with linespoints lw 2 dt 2 pt 6 lc rung_colour(k) title word(titles, k+1), \
     [1:256] 0.3/x with lines dt 3 lc "gray" title "slope -1"
set xlabel "CPU seconds (2 threads together)"
plot for [k=0:3] file using (column(1)==k ? $9 : 1/0):7 with linespoints lw 2 pt 7 lc rung_colour(k) title word(titles, k+1), \
     for [k=4:5] file using (column(1)==k ? $9 : 1/0):7 with linespoints lw 2 dt 2 pt 6 lc rung_colour(k) title word(titles, k+1)
unset multiplot
