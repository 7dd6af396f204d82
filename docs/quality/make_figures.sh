#!/usr/bin/env bash
# Redraws the paper's figures from loopfarm's own runs: docs/quality/figures/*.png,
# with the data beside them (*.csv, *.json). Every curve is one
# `loopfarm energy` run, printed here as it is run, so any of them can be
# repeated by hand.
#
#   docs/quality/make_figures.sh            # uses build/release/tools/loopfarm (builds it if missing)
#   LOOPFARM=/path/to/loopfarm docs/quality/make_figures.sh
#
# The same figures are asserted as tests in tests/core/paper_figures_test.cpp.
set -euo pipefail
cd "$(dirname "$0")/../.."

loopfarm="${LOOPFARM:-build/release/tools/loopfarm}"
if [[ ! -x "$loopfarm" ]]; then
  cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build/release -j"$(nproc)" --target loopfarm_cli
fi
command -v gnuplot >/dev/null || { echo "make_figures.sh: needs gnuplot (scripts/deps.sh installs it)" >&2; exit 1; }

out=docs/quality/figures
mkdir -p "$out"
samples=360
# The paper's loop (a = 2, 4, 2, 4; alpha = 30, 90, 30, 90 deg) from its start
# theta1 = 120, theta2 = 90 deg.
paper_start=(--alpha-deg 30,90,30,90 --theta-deg 120,90,-120,-90 --samples "$samples")

json_number() {  # json_number KEY FILE: a number from loopfarm's one-line JSON
  sed -n "s/.*\"$1\":\([^,}]*\).*/\1/p" "$2"
}

run() {  # run NAME ARGS...: one cycle into $out/NAME.csv and $out/NAME.json
  local name="$1"
  shift
  echo "+ loopfarm energy $* --csv $out/$name.csv --json" >&2
  "$loopfarm" energy "$@" --csv "$out/$name.csv" --json >"$out/$name.json"
}

# gnuplot: input angle wrapped to [0, 360), energy; skips the header row.
common='set datafile separator ","; set key top right; set grid;
set xlabel "input angle theta_1 [deg]"; set xrange [0:360]; set xtics 0,45,360;
set terminal pngcairo size 900,600 font ",11"'
wrapped='(x=$1 - 360*floor($1/360.0))'

# --- Fig. 6: the Bennett loop moves with zero energy ---------------------------
# Its energies are round-off (1e-32 .. 1e-27): below a job's zero threshold
# (1e-12) they are zero, and are drawn on the threshold's line, as `loopfarm
# energy --plot --log` draws them.
run fig6_bennett --a 2,4,2,4 "${paper_start[@]}"
fig6_max=$(printf "%.2g" "$(json_number E_max "$out/fig6_bennett.json")")
gnuplot <<EOF
$common
set output "$out/fig6_bennett.png"
set title "Fig. 6: Bennett loop a = (2,4,2,4), alpha = (30,90,30,90) deg: energy over the cycle\nE_max $fig6_max over $samples samples: round-off of a zero" noenhanced
set ylabel "E / (k_a L^2)"; set logscale y; set yrange [1e-13:1e-2]; set format y "10^{%L}"
set key outside bottom center horizontal
threshold = 1e-12
plot "$out/fig6_bennett.csv" every ::1 using $wrapped:(\$2 > threshold ? \$2 : threshold) with points pt 7 ps 0.5 lc rgb "#0072b2" title "E (below the threshold: drawn on it)", \
     threshold with lines dt 2 lw 1.5 lc rgb "#d55e00" title "zero threshold 1e-12 (a job's default)"
EOF

# --- Fig. 7: lengthening link 1 raises the energy as (da)^2 -------------------
: >"$out/fig7_peaks.dat"
plot_lines=""
for a1 in 2.00 2.02 2.04 2.06 2.08 2.10; do
  run "fig7_a1_$a1" --a "$a1,4,2,4" "${paper_start[@]}"
  printf '%s %s %s\n' "$a1" "$(json_number E_max "$out/fig7_a1_$a1.json")" "$(json_number E_mean "$out/fig7_a1_$a1.json")" >>"$out/fig7_peaks.dat"
  plot_lines+="\"$out/fig7_a1_$a1.csv\" every ::1 using $wrapped:2 smooth unique with lines lw 2 title \"a_1 = $a1\", "
done
gnuplot <<EOF
$common
set output "$out/fig7_lengthened_link.png"
set multiplot layout 1,2 title "Fig. 7: paper loop with link 1 lengthened"
set title "energy over the cycle"; set ylabel "E / (k_a L^2)"; set key outside bottom center horizontal
plot ${plot_lines%, }
unset xrange; set xtics auto; set logscale xy; set xlabel "a_1 - 2"; set ylabel "E_{max}"
set title "peak energy: slope 2 on log-log axes"
set format y "10^{%L}"; set datafile separator whitespace; set key inside bottom right vertical
set fit quiet; set fit logfile "/dev/null"
f(x) = c * x**2; c = 1.0
fit f(x) "$out/fig7_peaks.dat" every ::1 using (\$1-2):2 via c
plot "$out/fig7_peaks.dat" every ::1 using (\$1-2):2 with points pt 7 ps 1.5 title "E_{max}", f(x) with lines dt 2 title "c (a_1 - 2)^2"
unset multiplot
EOF

# --- Fig. 12: the two link-length combinations of the paper's optimisation -----
run fig12_L1_1.97_L2_4.03 --a 1.97,4.03,1.97,4.03 "${paper_start[@]}"
run fig12_L1_2.03_L2_4.01 --a 2.03,4.01,2.03,4.01 "${paper_start[@]}"
gnuplot <<EOF
$common
set output "$out/fig12_link_length_iteration.png"
set title "Fig. 12: energy over the cycle for two (L_1, L_2) of the link-length iteration"
set ylabel "E / (k_a L^2)"; set key outside bottom center horizontal
plot "$out/fig12_L1_1.97_L2_4.03.csv" every ::1 using $wrapped:2 smooth unique with lines lw 2 title "L_1 = 1.97, L_2 = 4.03 (E1)", \
     "$out/fig12_L1_2.03_L2_4.01.csv" every ::1 using $wrapped:2 smooth unique with lines lw 2 title "L_1 = 2.03, L_2 = 4.01 (E2)"
EOF

# --- Folded poses: cusps of the energy at theta1 = 0 and 180 deg -------------
run folded_a1_2.03 --a 2.03,4,2,4 "${paper_start[@]}"
gnuplot <<EOF
$common
set output "$out/folded_poses.png"
set title "a_1 = 2.03: flat-folded poses at theta_1 = 0 and 180 deg cost less (cusps), 1 deg samples"
set ylabel "E / (k_a L^2)"; set key bottom right; set format y "%.2e"
set arrow from 0,graph 0 to 0,graph 1 nohead dt 3; set arrow from 180,graph 0 to 180,graph 1 nohead dt 3
plot "$out/folded_a1_2.03.csv" every ::1 using $wrapped:2 smooth unique with linespoints pt 7 ps 0.4 title "E(theta_1)"
EOF

# --- Table 1: the zeros of the paper's search form a Bennett family -----------
# Every start of jobs/paper-table1.toml (Gauss-Newton), one JSON line each; the
# final (alpha1, alpha2) of each start against the family
# sin(alpha2)/a2 = sin(alpha1)/a1 at the extreme length ratios the scopes allow.
table1_starts=64
: >"$out/table1_starts.jsonl"
echo "+ for i in 0..$((table1_starts - 1)): loopfarm start jobs/paper-table1.toml --index \$i --json" >&2
for ((i = 0; i < table1_starts; ++i)); do
  "$loopfarm" start jobs/paper-table1.toml --index "$i" --json >>"$out/table1_starts.jsonl"
done
# One row per start: index, zero (1/0), a1, a2, alpha1_deg, alpha2_deg of the final geometry.
echo "# index zero a1 a2 alpha1_deg alpha2_deg" >"$out/table1_final.dat"
while IFS= read -r line; do
  index=$(sed -n 's/.*"index":\([0-9]*\).*/\1/p' <<<"$line")
  zero=$(sed -n 's/.*"zero":\(true\|false\).*/\1/p' <<<"$line")
  final=$(sed -n 's/.*"final_geometry":{"a":\[\([^],]*\),\([^],]*\),[^]]*\],"alpha_deg":\[\([^],]*\),\([^],]*\),.*/\1 \2 \3 \4/p' <<<"$line")
  echo "$index $([[ $zero == true ]] && echo 1 || echo 0) $final" >>"$out/table1_final.dat"
done <"$out/table1_starts.jsonl"
gnuplot <<EOF
$common
set output "$out/table1_bennett_family.png"
set title "Table 1 search: where $table1_starts Gauss-Newton starts end, against the Bennett family"
set xlabel "alpha_1 [deg]"; set ylabel "alpha_2 [deg]"; set xrange [0:180]; set yrange [0:180]
set datafile separator whitespace
set xtics 0,30,180; set ytics 0,30,180; set key outside bottom center horizontal maxrows 3
d2r = pi/180
r_lo = 3.96/2.05; r_hi = 4.05/1.96
f(x, r) = (r*sin(x*d2r) <= 1) ? asin(r*sin(x*d2r))/d2r : 1/0
set samples 2000
plot f(x, r_lo) with lines lc rgb "gray" title "sin(alpha_2) = (a_2/a_1) sin(alpha_1), a_2/a_1 = 3.96/2.05", \
     180 - f(x, r_lo) with lines lc rgb "gray" notitle, \
     f(x, r_hi) with lines dt 2 lc rgb "gray" title "a_2/a_1 = 4.05/1.96", \
     180 - f(x, r_hi) with lines dt 2 lc rgb "gray" notitle, \
     "$out/table1_final.dat" using (\$2 == 1 ? \$5 : 1/0):6 with points pt 7 ps 1.2 lc rgb "blue" title "zero", \
     "$out/table1_final.dat" using (\$2 == 0 ? \$5 : 1/0):6 with points pt 6 ps 1.2 lc rgb "red" title "not a zero", \
     "-" with points pt 3 ps 3 lc rgb "black" title "the paper's (30, 90) deg"
30 90
e
EOF

# The rigid loop's motion (docs/guide/motion.md): the non-Grashof four-bar
# 2, 3, 2.5, 4, whose input rocks between 50.16 and 309.84 deg.
echo "+ loopfarm motion --a 2,3,2.5,4 --alpha-deg 0,0,0,0 --plot $out/motion_triple_rocker.png" >&2
"$loopfarm" motion --a 2,3,2.5,4 --alpha-deg 0,0,0,0 --plot "$out/motion_triple_rocker.png" >/dev/null

echo "figures written to $out/" >&2
