# make plots: every figure drawn by a gnuplot script in plots/ from CSV that a
# program wrote under build/data/: plots/chNN_*.gp from chapter NN's program
# run with --data, plots/accel_*.gp from the benchmark.
#
# By default the experiments are quick: small images, few samples, short
# references, chapter 02's ray counts and chapters 04-06's structure counts:
# about 50 CPU-seconds in all, so that `make docs` builds the
# book in minutes; their curves are rough. `make plots FULL=1` runs them at
# full size (each chapter's defaults: about an hour on two cores) and the
# accelerator plots from `make bench`. Each run leaves its record,
# build/data/NAME.run ("quick" or "full", then the command), which the book
# prints under each plot. The --data runs write their images under
# build/data/, never over the build/out/ pictures that `make chNN` made.
# Beside a plot, plots/NAME.table (awk) writes build/plots/NAME.md: the
# table the chapter quotes, from the same CSV, with the run's command.

.PHONY: plots plot-data plot-tables

PLOT_SCRIPTS := $(sort $(wildcard plots/*.gp))
# The measured tables the chapters quote, from the same data (docs/splice.sh).
PLOT_TABLES := $(sort $(wildcard plots/*.table))
DATA_CHAPTERS := $(foreach c,$(CHAPTERS),$(if $(wildcard plots/ch$(call chapter_number,$(c))_*.gp),$(c)))

# Each chapter's quick flags (chapter 07's tables take a second as they are).
PLOT_QUICK_08 := --quick
PLOT_QUICK_09 := --experiment-size 32 --reference-spp 256 --experiment-spp 32
PLOT_QUICK_10 := --quick
PLOT_QUICK_11 := --experiment-size 16 --reference-spp 512 --experiment-seconds 0.5
PLOT_QUICK_12 := --quick
PLOT_MODE := $(if $(FULL),full,quick)
plot_flags = $(if $(FULL),,$(PLOT_QUICK_$(1)))

# The accelerator plots need the benchmark's CSV. `make bench` writes the
# full one (and its record); without it, a quick benchmark (1k and 10k
# triangles, one repetition, 2048 rays per set) makes it. FULL=1 runs
# `make bench` unless its full data is there.
BENCH_QUICK := $(BUILD)/bin/bench_accel --sizes 1024,10240 --reps 1 --max-rays 2048 \
  --out $(BUILD)/data/accel.csv --stadium $(BUILD)/data/stadium.csv
ACCEL_FULL_DONE := $(shell grep -qs '^full' $(BUILD)/data/accel.run && echo yes)
accel-data: $(BUILD)/bin/bench_accel $(if $(FULL),$(if $(ACCEL_FULL_DONE),,bench))
	@mkdir -p $(BUILD)/data
	@if [ -z "$(FULL)" ] && ! { [ -f $(BUILD)/data/accel.csv ] && [ -f $(BUILD)/data/stadium.csv ]; }; then \
	  echo "quick: $(subst $(BUILD)/,build/,$(BENCH_QUICK))"; $(BENCH_QUICK) > $(BUILD)/data/accel.log || exit 1; \
	  printf 'quick\t%s\n' "$(subst $(BUILD)/,build/,$(BENCH_QUICK))" > $(BUILD)/data/accel.run; \
	fi
.PHONY: accel-data

# MPIRUN="mpirun -np 4" (or with --hostfile, for several machines): chapter
# 09's references, the most expensive renders of the book, are rendered by
# that many ranks of the MPI build (make mpi, mk/mpi.mk), which then leave
# the measurements to rank 0. Each reference keeps a record of how it was
# made (NAME-record.txt: size, spp, seed, method, scene hash, version) and
# is made again when this run would make another, and an interrupted one
# resumes from its checkpoint. The other chapters run as one process.
MPIRUN ?=
MPI_CHAPTERS := 09
data_split = $(and $(MPIRUN),$(filter $(2),$(MPI_CHAPTERS)))
data_program = $(if $(data_split),$(MPIRUN) $(BUILD)/mpi/bin/$(1),$(BUILD)/bin/$(1))
data_shown = $(if $(data_split),$(MPIRUN) build/mpi/bin/$(1),build/bin/$(1))

# $(call data_run,NN-name): the chapter's --data run, its log and its record.
# A chapter without quick flags (07) always makes its full data.
data_mode = $(if $(PLOT_QUICK_$(1)),$(PLOT_MODE),full)
data_run = echo "$(call data_mode,$(2)): $(strip $(call data_shown,$(1),$(2)) --data build/data $(call plot_flags,$(2)))" && \
  $(call data_program,$(1),$(2)) --quiet --data $(BUILD)/data $(call plot_flags,$(2)) --out $(BUILD)/data/ch$(2).exr \
    > $(BUILD)/data/ch$(2).log && \
  printf '%s\t%s\n' $(call data_mode,$(2)) "$(strip $(call data_shown,$(1),$(2)) --data build/data $(call plot_flags,$(2)))" \
    > $(BUILD)/data/ch$(2).run

# Chapter 02 draws no plot but quotes one measured table (plots/ch02_depth.table):
# the rays its default scene costs at each depth limit, one render a depth,
# each writing its counters (build/data/ch02_depthN.counters.json). Counts,
# not times: they do not move with the machine's load.
CH02_DEPTHS := 0 1 2 3 5 10 64
ch02-data: $(BUILD)/bin/02-whitted
	@mkdir -p $(BUILD)/data
	@for d in $(CH02_DEPTHS); do \
	  $(BUILD)/bin/02-whitted --quiet --max-depth $$d --out $(BUILD)/data/ch02_depth$$d.exr || exit 1; done
	@printf 'full\tbuild/bin/02-whitted --max-depth N --out build/data/ch02_depthN.exr, N = %s\n' \
	  "$(CH02_DEPTHS)" > $(BUILD)/data/ch02.run
.PHONY: ch02-data

# Chapters 04, 05 and 06 quote their structures' own counts (cells, nodes,
# depth, references, tests per ray), each from its program's report on one
# render of the tori field or the stadium, one thread
# (build/data/chNN_RUN.log), read by plots/ch04_density.table,
# ch05_kdtree.table and ch06_split.table. Counts, not times: they do not move
# with the machine's load. About ten CPU-seconds in all.
CH04_RUNS := tori:1 tori:8 tori:27 tori:100 stadium:27 stadium:216
CH05_RUNS := tori-10240:2 tori-102400:1 tori-102400:2 tori-102400:3 tori-102400:4 stadium:2
CH06_RUNS := tori:median tori:sah stadium:median stadium:sah
structure-data: $(BUILD)/bin/04-uniform-grid $(BUILD)/bin/05-kd-tree $(BUILD)/bin/06-bvh
	@mkdir -p $(BUILD)/data
	@for r in $(CH04_RUNS); do m=$${r%%:*}; c=$${r#*:}; \
	  $(BUILD)/bin/04-uniform-grid --threads 1 --mesh $$m --density $$c --out $(BUILD)/data/ch04_$${m}_$$c.exr \
	    > $(BUILD)/data/ch04_$${m}_$$c.log || exit 1; done
	@printf 'full\tbuild/bin/04-uniform-grid --threads 1 --mesh M --density C, (M:C) = %s\n' "$(CH04_RUNS)" > $(BUILD)/data/ch04.run
	@for r in $(CH05_RUNS); do m=$${r%%:*}; c=$${r#*:}; n=$${m#tori-}; \
	  if [ $$m = stadium ]; then a="--mesh stadium"; else a="--triangles $$n"; fi; \
	  $(BUILD)/bin/05-kd-tree --threads 1 $$a --traversal-cost $$c --out $(BUILD)/data/ch05_$${m}_$$c.exr \
	    > $(BUILD)/data/ch05_$${m}_$$c.log || exit 1; done
	@printf 'full\tbuild/bin/05-kd-tree --threads 1 --triangles N|--mesh stadium --traversal-cost C, (N:C) = %s\n' "$(CH05_RUNS)" > $(BUILD)/data/ch05.run
	@for r in $(CH06_RUNS); do m=$${r%%:*}; s=$${r#*:}; \
	  $(BUILD)/bin/06-bvh --threads 1 --mesh $$m --split $$s --out $(BUILD)/data/ch06_$${m}_$$s.exr \
	    > $(BUILD)/data/ch06_$${m}_$$s.log || exit 1; done
	@printf 'full\tbuild/bin/06-bvh --threads 1 --mesh M --split S, (M:S) = %s\n' "$(CH06_RUNS)" > $(BUILD)/data/ch06.run
.PHONY: structure-data

# Chapter 03 quotes one measured table (plots/ch03_boxes.table): its tests
# per ray and time with and without the boxes, one render each.
CH03_SIZE := --width 160 --height 120
ch03-data: $(BUILD)/bin/03-aabb-slabs
	@mkdir -p $(BUILD)/data
	@$(BUILD)/bin/03-aabb-slabs --quiet --threads 1 $(CH03_SIZE) --no-boxes --out $(BUILD)/data/ch03_noboxes.exr
	@$(BUILD)/bin/03-aabb-slabs --quiet --threads 1 $(CH03_SIZE) --out $(BUILD)/data/ch03_boxes.exr
	@printf 'full\tbuild/bin/03-aabb-slabs --threads 1 %s [--no-boxes]\n' "$(CH03_SIZE)" > $(BUILD)/data/ch03.run
.PHONY: ch03-data

# Chapter 13 quotes one measured table (plots/ch13_steps.table): what each
# step buys, from one run of its --bench (the steps side by side, 1 and 2
# threads taking turns, best of five). Times: they move with the machine's
# load, so the table says which run made them.
CH13_BENCH := $(if $(FULL),--width 256 --spp 16,--width 128 --spp 4)
ch13-data: $(BUILD)/bin/13-production
	@mkdir -p $(BUILD)/data
	@$(BUILD)/bin/13-production --bench $(CH13_BENCH) --bench-csv $(BUILD)/data/ch13_steps.csv > $(BUILD)/data/ch13_steps.log
	@printf '%s\tbuild/bin/13-production --bench %s --bench-csv build/data/ch13_steps.csv\n' $(PLOT_MODE) \
	  "$(CH13_BENCH)" > $(BUILD)/data/ch13.run
.PHONY: ch13-data

plot-data: $(foreach c,$(DATA_CHAPTERS),$(BUILD)/bin/$(c)) $(if $(wildcard plots/accel_*.gp),accel-data) $(if $(MPIRUN),mpi) ch02-data ch03-data structure-data ch13-data
	@mkdir -p $(BUILD)/data
	@$(foreach c,$(DATA_CHAPTERS),$(call data_run,$(c),$(call chapter_number,$(c))) && ) true

plots: plot-data
	@mkdir -p $(BUILD)/plots
	@for s in $(PLOT_SCRIPTS); do \
	  echo "gnuplot $$s"; \
	  gnuplot -e "data_dir='$(BUILD)/data'; plot_dir='$(BUILD)/plots'" $$s || exit 1; \
	done
	@$(MAKE) --no-print-directory plot-tables
	@echo "Plots are in $(BUILD)/plots/ (PNG and SVG), from $(PLOT_MODE) data (make plots FULL=1: full size)."

# The measured tables alone, from the data there is (make plots has run).
plot-tables:
	@mkdir -p $(BUILD)/plots
	@for t in $(PLOT_TABLES); do \
	  name=$$(basename $$t .table); rec=$(BUILD)/data/$${name%%_*}.run; \
	  { awk -v data_dir='$(BUILD)/data' -f plots/tables.awk -f plots/structures.awk -f $$t && \
	    if [ -f $$rec ]; then echo && \
	    printf '*Measured by the run that drew the figure: `%s` (%s data%s).*\n' "$$(cut -f2 $$rec)" \
	      "$$(cut -f1 $$rec)" "$$(grep -q ^quick $$rec && echo ': a smaller, rougher run; make plots FULL=1 for the full size')"; fi; \
	  } > $(BUILD)/plots/$$name.md.tmp && mv $(BUILD)/plots/$$name.md.tmp $(BUILD)/plots/$$name.md || exit 1; \
	  echo "awk -f $$t > build/plots/$$name.md"; \
	done
