# make bench: the acceleration structures timed beside Embree, and the path
# tracer, also on Embree's kernels (figures and CSV under build/data/).

.PHONY: bench bench-deps

# The Embree harness lives in ../shared/anchors (beside this repository); it
# is built here, never copied in. Embree itself comes from Debian.
SHARED ?= ../shared
BENCH_SIZES ?= 1024 10240 102400 1048576
BENCH_REPS ?= 3
comma := ,
empty :=
space := $(empty) $(empty)

$(BUILD)/bin/bench_accel: $(BUILD)/obj/tests/bench_accel.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

$(BUILD)/bin/embree_bench: $(SHARED)/anchors/embree_bench.c | bench-deps
	@mkdir -p $(dir $@)
	$(CC) -O2 -std=c99 -Wall $< -o $@ -lembree3 -lm

# Chapter 09's path tracer with its rays traced by Embree beside ours
# (tests/bench_pt_embree.c): built only here, and only where Embree's
# header is installed (`make bench-deps`).
EMBREE_HEADER := $(wildcard /usr/include/embree3/rtcore.h)
$(BUILD)/bin/bench_pt_embree: $(BUILD)/obj/tests/bench_pt_embree.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -lembree3 -o $@

# Embree and ours, one after the other, on the same machine in one run; then
# the path tracer's seconds per million camera samples (chapter 09), and the
# same path tracer on Embree's kernels. The Embree programs are built only
# where their sources (EMBREE_HARNESS) and header (EMBREE_HEADER) are; as
# prerequisites, not by a make inside the recipe, which make -n would run.
EMBREE_HARNESS := $(wildcard $(SHARED)/anchors/embree_bench.c)
bench: $(BUILD)/bin/bench_accel $(BUILD)/bin/13-production \
       $(if $(EMBREE_HARNESS),$(BUILD)/bin/embree_bench) $(if $(EMBREE_HEADER),$(BUILD)/bin/bench_pt_embree)
	@mkdir -p $(BUILD)/data
ifneq ($(EMBREE_HARNESS),)
	@rm -f $(BUILD)/data/embree.txt
	@for n in $(BENCH_SIZES); do \
	  $(BUILD)/bin/embree_bench embree $$n medium 1 $(BENCH_REPS) | tee -a $(BUILD)/data/embree.txt; \
	done
else
	@echo "no $(SHARED)/anchors/embree_bench.c: timing without Embree"
endif
	$(BUILD)/bin/bench_accel --sizes $(subst $(space),$(comma),$(strip $(BENCH_SIZES))) --reps $(BENCH_REPS) \
	  --out $(BUILD)/data/accel.csv --stadium $(BUILD)/data/stadium.csv $(if $(EMBREE_HARNESS),--embree $(BUILD)/data/embree.txt)
	@printf 'full\t%s\n' "make bench (build/bin/bench_accel --sizes $(subst $(space),$(comma),$(strip $(BENCH_SIZES))) --reps $(BENCH_REPS))" \
	  > $(BUILD)/data/accel.run
	$(BUILD)/bin/13-production --bench --width 256 --spp 16 --bench-csv $(BUILD)/data/ch13_speed.csv
ifneq ($(EMBREE_HEADER),)
	$(BUILD)/bin/bench_pt_embree --width 256 --spp 16 --data $(BUILD)/data
else
	@echo "no Embree header (make bench-deps): the path tracer on Embree skipped"
endif

bench-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="libembree-dev"
