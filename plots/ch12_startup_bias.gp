# Start-up bias: short Metropolis runs on the Cornell box (many chains, few
# mutations each), every chain started at a bootstrap path picked in
# proportion to f, or every chain started at the same fixed path. relMSE
# against the reference (mean of a few runs) as a function of CPU seconds.
# Data: build/bin/12-metropolis --data DIR  ->  DIR/ch12_startup_bias.csv
set datafile separator ","
set logscale xy
set grid
set key top right
set xlabel "CPU seconds (2 threads together)"
set ylabel "relMSE against the reference"
set format y "10^{%L}"
file = data_dir."/ch12_startup_bias.csv"
do for [fmt in "png svg"] {
    if (fmt eq "png") { set terminal pngcairo size 700,450 font ",10" } else { set terminal svg size 700,450 }
    set output plot_dir."/ch12_startup_bias.".fmt
    set title "Start-up bias of short Metropolis runs (Cornell box)"
    plot file using (column(1)==0 ? $5 : 1/0):6 with linespoints lw 2 pt 7 title "chains start at bootstrap paths", \
         file using (column(1)==1 ? $5 : 1/0):6 with linespoints lw 2 pt 7 title "all chains start at one fixed path"
}
