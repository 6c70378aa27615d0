# SPDX-License-Identifier: MIT
# speed_accuracy.gp: the speed/accuracy chart of bspf_sweep's CSV (the rows of
# level "all": every level pooled). Two panels, x = ns per agent-step (log):
# left the p99 and the largest penetration (fraction of the body's size),
# right the p99 per-step deviation from the reference end (fraction of the
# xz radius). One point per method and setting, the default setting of each
# method ringed in black; each label is the setting and "inside/refused"
# (agent-frames inside a solid / refused moves). bench/chart_labels.py lays
# the labels out so that none overlaps (a line joins a label moved away from
# its point) and chooses the axis ranges, both on the fixed margins below.
#
#   python3 bench/chart_labels.py docs/speed-accuracy.csv /tmp/layout
#   gnuplot -e "csv='docs/speed-accuracy.csv'; layout='/tmp/layout'; out='docs/speed-accuracy'" bench/speed_accuracy.gp
#
# writes OUT.svg and OUT.png (scripts/chart.sh runs both steps). Zeros cannot
# sit on a log axis: values below the floor are drawn at the floor (said in
# the axis labels).
if (!exists("csv")) csv = 'docs/speed-accuracy.csv'
if (!exists("out")) out = 'docs/speed-accuracy'
if (!exists("layout")) layout = '/tmp/speed-accuracy-layout'
load layout.'.gp'

set datafile separator ','
set datafile commentschars '#'

penFloor = 1e-4
devFloor = 1e-4
methods = 'planes exact bullet'

isAll(m) = strcol(1) eq 'all' && strcol(2) eq m
isDefault(m) = isAll(m) && strcol(3) eq 'default'
clamp(y, f) = y < f ? f : y

# Columns: 9 ns_per_step, 11 penetration_p99, 12 penetration_max,
# 16 deviation_p99_frac.
set logscale x
set logscale y
set xrange [xmin:xmax]
set grid xtics ytics mxtics mytics lc rgb '#e4e4e4'
set xlabel 'ns per agent-step (log)'
set format y '%g'
set key box opaque
set style line 1 pt 7 ps 0.9 lc rgb '#1f77b4'
set style line 2 pt 5 ps 0.9 lc rgb '#d62728'
set style line 3 pt 9 ps 1.1 lc rgb '#2ca02c'
set style line 4 pt 6 ps 2.6 lw 1.5 lc rgb '#000000'

# The labels: layout.dat rows (comma-separated) are panel, method, point x, y, label x, y,
# text, default (1 for the default setting, drawn bold).
lay = layout.'.dat'
onPanel(p, m) = ($1 == p && $2 == m)

do for [fmt in "svg png"] {
  if (fmt eq 'svg') {
    set terminal svg size 1400,720 fixed enhanced font 'sans,11' background rgb 'white'
  } else {
    set terminal pngcairo size 1400,720 enhanced font 'sans,9' background rgb 'white'
  }
  set output out.'.'.fmt
  set multiplot title sprintf('bspf speed against accuracy: all %s levels pooled (labels: setting, inside-solid agent-frames / refused moves; ringed: default setting)', levels)
  set key top left
  set bmargin at screen 0.10
  set tmargin at screen 0.88

  # Left: p99 penetration (filled) and the largest (open, labelled unless at
  # the floor: the p99 is 0 for most settings).
  set lmargin at screen 0.075
  set rmargin at screen 0.475
  set yrange [ymin1:ymax1]
  set ylabel sprintf('penetration, fraction of the body size: p99 filled, max open (< %g drawn at %g)', penFloor, penFloor)
  set datafile separator ','
  plot for [i=1:3] csv using (isAll(word(methods, i)) ? $9 : NaN):(clamp($11, penFloor)) \
         with points ls i title word(methods, i).' p99', \
       for [i=1:3] csv using (isAll(word(methods, i)) ? $9 : NaN):(clamp($12, penFloor)) \
         with points ls i pt (word('6 4 8', i) + 0) title word(methods, i).' max', \
       for [i=1:3] csv using (isDefault(word(methods, i)) ? $9 : NaN):(clamp($12, penFloor)) \
         with points ls 4 notitle, \
       csv using (isAll('planes') && strcol(3) eq 'default' ? $9 : NaN):(clamp($12, penFloor)) \
         with points ls 4 title 'default setting', \
       for [i=0:2] lay using (onPanel(1, i) ? $3 : NaN):4:($5 - $3):($6 - $4) \
         with vectors nohead lw 0.5 lc rgb '#999999' notitle, \
       for [i=0:2] lay using (onPanel(1, i) && $8 == 0 ? $5 : NaN):6:7 \
         with labels left font ',8' tc ls (i + 1) notitle, \
       for [i=0:2] lay using (onPanel(1, i) && $8 == 1 ? $5 : NaN):6:7 \
         with labels left font 'sans:Bold,8' tc ls (i + 1) notitle

  # Right: p99 deviation per step (its top left is crowded).
  set key bottom right
  set lmargin at screen 0.575
  set rmargin at screen 0.975
  set yrange [ymin2:ymax2]
  set ylabel sprintf('p99 deviation per step from the reference, fraction of radius xz (< %g drawn at %g)', devFloor, devFloor)
  plot for [i=1:3] csv using (isAll(word(methods, i)) ? $9 : NaN):(clamp($16, devFloor)) \
         with points ls i title word(methods, i), \
       for [i=1:3] csv using (isDefault(word(methods, i)) ? $9 : NaN):(clamp($16, devFloor)) \
         with points ls 4 notitle, \
       csv using (isAll('planes') && strcol(3) eq 'default' ? $9 : NaN):(clamp($16, devFloor)) \
         with points ls 4 title 'default setting', \
       for [i=0:2] lay using (onPanel(2, i) ? $3 : NaN):4:($5 - $3):($6 - $4) \
         with vectors nohead lw 0.5 lc rgb '#999999' notitle, \
       for [i=0:2] lay using (onPanel(2, i) && $8 == 0 ? $5 : NaN):6:7 \
         with labels left font ',8' tc ls (i + 1) notitle, \
       for [i=0:2] lay using (onPanel(2, i) && $8 == 1 ? $5 : NaN):6:7 \
         with labels left font 'sans:Bold,8' tc ls (i + 1) notitle
  unset multiplot
  unset output
}
