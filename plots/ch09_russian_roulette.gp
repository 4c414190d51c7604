# Russian roulette: the probability P_RR of continuing a path trades time
# (rays per sample) against variance. Efficiency = 1 / (MSE x time).
# Data: build/bin/09-path-tracing --data DIR  ->  DIR/ch09_russian_roulette.csv
set datafile separator ","
file = data_dir."/ch09_russian_roulette.csv"
do for [t=1:2] {
  if (t == 1) { set terminal pngcairo size 1000,450 font ",10"; set output plot_dir."/ch09_russian_roulette.png" }
  if (t == 2) { set terminal svg size 1000,450; set output plot_dir."/ch09_russian_roulette.svg" }
  set multiplot layout 1,2 title "Russian roulette with a fixed P_{RR} (cosine rung)"
  set grid
  set key top left
  set xlabel "P_{RR}"
  set ylabel "rays per camera sample"
  set y2label "MSE against the reference"
  set y2tics
  set ytics nomirror
  plot file using 1:5 skip 1 with linespoints lw 2 pt 7 title "rays per sample (cost)", \
       file using 1:3 skip 1 axes x1y2 with linespoints lw 2 pt 5 title "MSE (noise)"
  unset y2label
  unset y2tics
  set ytics mirror
  set ylabel "efficiency 1 / (MSE x CPU seconds)"
  plot file using 1:4 skip 1 with linespoints lw 2 pt 7 title "efficiency"
  unset multiplot
}
