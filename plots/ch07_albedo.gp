# ch07_albedo.gp -- the BRDF energy check: directional albedo against viewing angle.
# Above 1, a surface reflects more light than it receives.
# Data: ch07_albedo.csv from build/bin/07-radiometry --data DIR.
# Run: gnuplot -e "data_dir='build/data'; plot_dir='build/plots'" plots/ch07_albedo.gp
if (!exists("data_dir")) data_dir = "build/data"
if (!exists("plot_dir")) plot_dir = "build/plots"
file = data_dir."/ch07_albedo.csv"
set datafile separator ","

do for [format in "png svg"] {
    if (format eq "png") { set terminal pngcairo size 900,600 font ",10" } else { set terminal svg size 900,600 font ",10" }
    set output plot_dir."/ch07_albedo.".format
    set title "BRDF energy check: albedo(theta_o) = integral of f_r cos theta_i d omega_i must stay <= 1"
    set xlabel "viewing angle theta_o from the normal (degrees)"
    set ylabel "directional albedo (fraction of the light reflected)"
    set xrange [0:90]
    set yrange [0:2.8]
    set xtics 15
    set grid
    set key at graph 0.98, graph 0.84 box opaque
    set object 1 rect from 0,1 to 90,2.8 fc rgb "#fde0dd" fs solid 0.5 noborder behind
    set label 1 "gains energy" at 3,1.1 tc rgb "#a50f15"
    plot 1 with lines lw 2 dt 2 lc rgb "#a50f15" title "1: energy conservation limit", \
         file skip 1 using 1:6 with lines lw 2 lc rgb "#6a51a3" title "chapter 01 shading read as a BRDF (kd 0.75, ks 0.5, p 64)", \
         file skip 1 using 1:4 with lines lw 2 lc rgb "#d95f02" title "Blinn-Phong kd/pi + ks (n.h)^p, kd 0.5, ks 2, p 32", \
         file skip 1 using 1:3 with lines lw 2 lc rgb "#1b9e77" title "Blinn-Phong kd 0.5, ks 0.5, p 32", \
         file skip 1 using 1:5 with lines lw 2 lc rgb "#e7298a" title "glossy mirror rho 0.9, p 200", \
         file skip 1 using 1:2 with lines lw 2 lc rgb "#08519c" title "Lambertian rho 0.8"
    unset output
}
