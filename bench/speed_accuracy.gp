# SPDX-License-Identifier: MIT
# speed_accuracy.gp: the speed/accuracy chart of bspf_sweep's CSV (the rows of
# level "all": every level pooled). Two panels, x = ns per agent-step (log):
# left the p99 and the largest penetration (fraction of the body's size),
# right the p99 per-step deviation from the reference end (fraction of the
# xz radius). One point per method and setting; each label is the setting and
# "inside/refused" (agent-frames inside a solid / refused moves).
#
#   gnuplot -e "csv='docs/speed-accuracy.csv'; out='docs/speed-accuracy'" bench/speed_accuracy.gp
#
# writes OUT.svg and OUT.png. Zeros cannot sit on a log axis: values below
# the floor are drawn at the floor (said in the axis labels).
if (!exists("csv")) csv = 'docs/speed-accuracy.csv'
if (!exists("out")) out = 'docs/speed-accuracy'

set datafile separator ','
set datafile commentschars '#'

penFloor = 1e-4
devFloor = 1e-4

isAll(m) = strcol(1) eq 'all' && strcol(2) eq m
short(k, v) = k eq 'default' ? 'default' : (k eq 'iterations' ? 'it '.v : k.' '.v)
label(m) = isAll(m) ? sprintf('%s %s/%s', short(strcol(3), strcol(4)), strcol(17), strcol(18)) : ''
clamp(y, f) = y < f ? f : y

# Columns: 9 ns_per_step, 11 penetration_p99, 16 deviation_p99_frac.
set logscale x
set logscale y
set grid xtics ytics mxtics mytics lc rgb '#dddddd'
set xlabel 'ns per agent-step (log)'
set key top right box opaque
set style line 1 pt 7 ps 0.9 lc rgb '#1f77b4'
set style line 2 pt 5 ps 0.9 lc rgb '#d62728'
set style line 3 pt 9 ps 1.1 lc rgb '#2ca02c'

do for [fmt in "svg png"] {
  if (fmt eq 'svg') {
    set terminal svg size 1400,640 dynamic enhanced font 'sans,11' background rgb 'white'
  } else {
    set terminal pngcairo size 1400,640 enhanced font 'sans,9' background rgb 'white'
  }
  set output out.'.'.fmt
  set multiplot layout 1,2 title 'bspf speed against accuracy: all levels pooled (labels: setting inside/refused)'
  # Left: p99 penetration (filled) and the largest (open, labelled unless at
  # the floor: the p99 is 0 for most settings).
  set ylabel sprintf('penetration, fraction of the body size: p99 filled, max open (< %g drawn at %g)', penFloor, penFloor)
  set yrange [penFloor / 2:*]
  plot for [i=1:3] csv using (isAll(word('planes exact bullet', i)) ? $9 : NaN):(clamp($11, penFloor)) \
         with points ls i title word('planes exact bullet', i).' p99', \
       for [i=1:3] csv using (isAll(word('planes exact bullet', i)) ? $9 : NaN):(clamp($12, penFloor)) \
         with points ls i pt (word('6 4 8', i) + 0) title word('planes exact bullet', i).' max', \
       for [i=1:3] csv using (isAll(word('planes exact bullet', i)) ? $9 : NaN):(clamp($12, penFloor)):($12 >= penFloor ? label(word('planes exact bullet', i)) : '') \
         with labels left offset 0.6,0.3 font ',7' tc ls i notitle
  set yrange [devFloor / 2:*]
  set ylabel sprintf('p99 deviation per step from the reference, fraction of radius xz (< %g drawn at %g)', devFloor, devFloor)
  plot for [i=1:3] csv using (isAll(word('planes exact bullet', i)) ? $9 : NaN):(clamp($16, devFloor)) \
         with points ls i title word('planes exact bullet', i), \
       for [i=1:3] csv using (isAll(word('planes exact bullet', i)) ? $9 : NaN):(clamp($16, devFloor)):(label(word('planes exact bullet', i))) \
         with labels left offset 0.6,0.3 font ',7' tc ls i notitle
  unset multiplot
  unset output
}
