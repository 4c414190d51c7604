# make plots: every figure drawn by a gnuplot script in plots/ from CSV that a
# program wrote under build/data/: plots/chNN_*.gp from chapter NN's program
# run with --data, plots/accel_*.gp from the benchmark.

.PHONY: plots plot-data

PLOT_SCRIPTS := $(sort $(wildcard plots/*.gp))
DATA_CHAPTERS := $(foreach c,$(CHAPTERS),$(if $(wildcard plots/ch$(call chapter_number,$(c))_*.gp),$(c)))

# The accelerator plots need the benchmark's CSV. When `make bench` has not
# been run, a quick one (up to 100k triangles, one repetition) makes it.
$(BUILD)/data/accel.csv $(BUILD)/data/stadium.csv &:
	@echo "no $@ yet: a quick benchmark (1k-100k triangles, 1 repetition); make bench runs all sizes"
	@$(MAKE) --no-print-directory bench BENCH_SIZES="1024 10240 102400" BENCH_REPS=1

plot-data: $(foreach c,$(DATA_CHAPTERS),$(BUILD)/bin/$(c)) $(if $(wildcard plots/accel_*.gp),$(BUILD)/data/accel.csv $(BUILD)/data/stadium.csv)
	@mkdir -p $(BUILD)/data $(BUILD)/out
	@for c in $(DATA_CHAPTERS); do \
	  n=$${c%%-*}; echo "$(BUILD)/bin/$$c --data $(BUILD)/data"; \
	  $(BUILD)/bin/$$c --quiet --data $(BUILD)/data --out $(BUILD)/out/ch$$n.exr || exit 1; \
	done

plots: plot-data
	@mkdir -p $(BUILD)/plots
	@for s in $(PLOT_SCRIPTS); do \
	  echo "gnuplot $$s"; \
	  gnuplot -e "data_dir='$(BUILD)/data'; plot_dir='$(BUILD)/plots'" $$s || exit 1; \
	done
	@echo "Plots are in $(BUILD)/plots/ (PNG and SVG)."
