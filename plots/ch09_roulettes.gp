# The references' roulettes against the lecture's: rays per camera sample
# (the price), MSE against the reference (what the price buys; the bar spans
# the lowest and highest of eight renders) and efficiency 1 / (MSE x time).
# Data: build/bin/09-path-tracing --data DIR  ->  DIR/ch09_roulettes.csv
set datafile separator ","
file = data_dir."/ch09_roulettes.csv"
do for [t=1:2] {
  if (t == 1) { set terminal pngcairo size 1000,450 font ",10"; set output plot_dir."/ch09_roulettes.png" }
  if (t == 2) { set terminal svg size 1000,450; set output plot_dir."/ch09_roulettes.svg" }
  set multiplot layout 1,2 title "Four roulettes on the Cornell box (lecture rung, at most 50 bounces)"
  set grid ytics
  set key below
  set style fill solid 0.5
  set boxwidth 0.4
  set xtics rotate by -20 offset -1,0
  set xrange [-0.6:3.6]
  set ylabel "rays per camera sample"
  set y2label "MSE against the reference"
  set y2tics
  set ytics nomirror
  set yrange [0:*]
  set y2range [0:*]
  plot file using ($0 - 0.2):8:xtic(2) skip 1 with boxes lc rgb "#4477aa" title "rays per sample (cost)", \
       file using ($0 + 0.2):4:5:6 skip 1 axes x1y2 with yerrorbars lw 2 pt 7 lc rgb "#cc6677" title "MSE, lowest to highest of 8 (noise)"
  unset y2label
  unset y2tics
  set ytics mirror
  set ylabel "efficiency 1 / (MSE x CPU seconds)"
  plot file using 0:7:xtic(2) skip 1 with boxes lc rgb "#228833" title "efficiency"
  unset multiplot
}
