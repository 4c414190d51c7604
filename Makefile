# The whole project in one non-recursive Makefile.
#
#   make demo        install missing Debian packages, build, render every chapter
#   make test        build and run every cmocka suite
#   make chNN        build and run chapter NN          (make ch01)
#   make test-chNN   build and run chapter NN's tests  (make test-ch01)
#   make sanitize    the test suites under AddressSanitizer + UndefinedBehaviorSanitizer
#   make test-seeds  every random test over 200 seeds: how many runs fail
#   make bench       time the acceleration structures beside Embree, and the path tracer, also on Embree's kernels (figures, CSV)
#   make plots       draw every figure (gnuplot) from data the programs write
#   make fuzz        run each parser's fuzz target for FUZZ_SECONDS
#   make valgrind    one small render of each chapter program under valgrind
#   make docs        the book: one HTML page per chapter, woven by pandoc, in build/docs/
#   make test-docs   render every page of the book in headless Chromium and check it
#   make help        everything else
#
# Everything generated goes under build/.

BUILD ?= build
CC ?= cc
OPT ?= -O2
# -ffp-contract=off: no fused multiply-add unless we write one. Contraction
# changes rounding differently in different places, which breaks the
# guarantees the robust geometry tests check (watertight triangles, ray
# offsets), and makes results differ between compilers. Never -ffast-math:
# it assumes NaN and Inf never happen, so the NaN guards would be removed.
CFLAGS ?= $(OPT) -g
ALL_CFLAGS = -std=c11 -D_DEFAULT_SOURCE -Wall -Wextra -Wpedantic -ffp-contract=off -fopenmp \
             -MMD -MP $(SANITIZE_FLAGS) $(CFLAGS)
CPPFLAGS += -Icommon -Ichapters -I/usr/include/OpenEXR
LDFLAGS += -fopenmp $(SANITIZE_FLAGS)
LDLIBS += -lOpenEXRCore -lstb -lm
TEST_LDLIBS = -lcmocka

# Debian packages the build, the tests and the plots need (by name).
DEBIAN_PACKAGES := gcc make libcmocka-dev libopenexr-dev libstb-dev gnuplot-nox

.DEFAULT_GOAL := all
.PHONY: all demo test sanitize valgrind valgrind-deps fuzz fuzz-deps deps bench-deps help clean bench plots plot-data docs docs-deps test-docs
.DELETE_ON_ERROR:

# ---------------------------------------------------------------- sources --
COMMON_SRC := $(sort $(wildcard common/*.c))
CHAPTERS := $(sort $(notdir $(wildcard chapters/[0-9][0-9]-*)))
chapter_number = $(firstword $(subst -, ,$(1)))

obj = $(patsubst %.c,$(BUILD)/obj/%.o,$(1))
COMMON_LIB := $(BUILD)/lib/libcommon.a

$(BUILD)/obj/%.o: %.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(CPPFLAGS) -c $< -o $@

$(COMMON_LIB): $(call obj,$(COMMON_SRC))
	@mkdir -p $(dir $@)
	@rm -f $@
	ar rcs $@ $^

# One chapter: a static library of what it introduces (every .c but main.c)
# and one program. It may use common/ and earlier chapters only, so it links
# against its own library and those of the chapters before it.
define CHAPTER_RULES
$(1)_NUM := $(call chapter_number,$(1))
$(1)_SRC := $$(filter-out chapters/$(1)/main.c,$$(sort $$(wildcard chapters/$(1)/*.c)))
$(1)_LIB := $(BUILD)/lib/libch$$($(1)_NUM).a
# Libraries to link, latest chapter first (static libraries resolve left to right).
$(1)_LIBS := $$($(1)_LIB) $$(LINK_SO_FAR) $(COMMON_LIB)
LINK_SO_FAR := $$($(1)_LIB) $$(LINK_SO_FAR)

$$($(1)_LIB): $$(call obj,$$($(1)_SRC))
	@mkdir -p $$(dir $$@)
	@rm -f $$@
	ar rcs $$@ $$^

$(BUILD)/bin/$(1): $$(call obj,chapters/$(1)/main.c) $$($(1)_LIBS)
	@mkdir -p $$(dir $$@)
	$$(CC) $$(LDFLAGS) $$^ $$(LDLIBS) -o $$@

$(BUILD)/tests/test_ch$$($(1)_NUM): $$(call obj,tests/test_ch$$($(1)_NUM).c) $$($(1)_LIBS)
	@mkdir -p $$(dir $$@)
	$$(CC) $$(LDFLAGS) $$^ $$(LDLIBS) $$(TEST_LDLIBS) -o $$@

.PHONY: ch$$($(1)_NUM) test-ch$$($(1)_NUM)
ch$$($(1)_NUM): $(BUILD)/bin/$(1)
	@mkdir -p $(BUILD)/out
	$(BUILD)/bin/$(1) --out $(BUILD)/out/ch$$($(1)_NUM).exr $$(ARGS)

test-ch$$($(1)_NUM): $(BUILD)/tests/test_ch$$($(1)_NUM)
	@$(BUILD)/tests/test_ch$$($(1)_NUM)

PROGRAMS += $(BUILD)/bin/$(1)
DEMOS += ch$$($(1)_NUM)
endef
LINK_SO_FAR :=
$(foreach c,$(CHAPTERS),$(eval $(call CHAPTER_RULES,$(c))))

# Everything the chapters built, latest first: what benchmarks link.
ALL_LIBS := $(LINK_SO_FAR) $(COMMON_LIB)

# Suites of common/ (every tests/test_*.c that is not a chapter's) link common/ only.
COMMON_TEST_SRC := $(filter-out tests/test_ch%,$(sort $(wildcard tests/test_*.c)))
COMMON_TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(COMMON_TEST_SRC))
$(COMMON_TESTS): $(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(COMMON_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) $(TEST_LDLIBS) -o $@

CHAPTER_TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(sort $(wildcard tests/test_ch[0-9][0-9].c)))
TESTS := $(COMMON_TESTS) $(CHAPTER_TESTS)

# Programs that only draw the book's figures (docs/figures/*.c), linked like a
# benchmark; built by `make all` too, so a change that breaks them shows at once.
DOC_PROGRAMS := $(patsubst docs/figures/%.c,$(BUILD)/bin/%,$(sort $(wildcard docs/figures/*.c)))
$(DOC_PROGRAMS): $(BUILD)/bin/%: $(BUILD)/obj/docs/figures/%.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

# ---------------------------------------------------------------- targets --
all: $(PROGRAMS) $(TESTS) $(DOC_PROGRAMS)
	@mkdir -p $(BUILD)/out

demo: $(PROGRAMS)
	@$(MAKE) --no-print-directory $(DEMOS)
	@echo "Images are in $(BUILD)/out/: open the .png previews, or the .exr files in an EXR viewer."

# Runs every suite even when one fails, then the checks that are scripts:
# the programs fed bad input (tests/bad_input.sh) and the hard-case catalog
# naming only tests that exist (tests/check_catalog.sh). One summary line.
test: $(TESTS) $(PROGRAMS)
	@passed=0; failed=0; bad=""; \
	for t in $(TESTS); do \
	  echo "== $$t"; \
	  $$t > $$t.log 2>&1; status=$$?; cat $$t.log; \
	  p=$$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' $$t.log | tail -1); \
	  f=$$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' $$t.log | tail -1); \
	  passed=$$((passed + $${p:-0})); failed=$$((failed + $${f:-0})); \
	  if [ $$status -ne 0 ]; then bad="$$bad $$t"; [ -n "$$f" ] || failed=$$((failed + 1)); fi; \
	done; \
	for s in $(TEST_SCRIPTS); do \
	  echo "== $$s"; \
	  if $$s $(BUILD); then passed=$$((passed + 1)); else failed=$$((failed + 1)); bad="$$bad $$s"; fi; \
	done; \
	echo; echo "$$passed passed, $$failed failed"; \
	if [ -n "$$bad" ]; then echo "failing suites:$$bad"; exit 1; fi

# Checks that are shell scripts, each given the build directory.
TEST_SCRIPTS := tests/bad_input.sh $(wildcard tests/check_catalog.sh)

# Every random test (those that take their seed from test_seed() in
# tests/test_support.h) over SEEDS other seeds, JOBS at a time: how many of
# the runs fail, per test. Not part of `make test` (about 40 minutes on
# two busy cores for 200 seeds).
SEEDS ?= 200
JOBS ?= 2
SEED_TESTS ?= .
.PHONY: test-seeds
test-seeds: $(TESTS)
	@tests/test_seeds.sh $(BUILD) $(SEEDS) $(JOBS) '$(SEED_TESTS)'

# The same suites built with AddressSanitizer and UndefinedBehaviorSanitizer,
# in a build directory of their own. Any report fails the run.
sanitize:
	@$(MAKE) --no-print-directory test BUILD=$(BUILD)/sanitize OPT=-O1 \
	  SANITIZE_FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"

# What -ffp-contract=off protects: chapter 01's leak test built once more with
# fused multiply-add allowed and available (-mfma -ffp-contract=fast), in a
# build directory of its own. The watertight test's edge functions a*b - c*d
# then round differently for the two triangles of an edge, and rays leak.
# Reports the counts; its exit status is the leak test's (expected to fail).
.PHONY: fp-contract-leaks
fp-contract-leaks:
	@grep -q -w fma /proc/cpuinfo || { echo "this CPU has no FMA instructions: nothing to show"; exit 0; }
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/fp-contract CFLAGS="$(OPT) -g -mfma -ffp-contract=fast" \
	  $(BUILD)/fp-contract/tests/test_ch01 >/dev/null
	@echo "chapter 01 built with -mfma -ffp-contract=fast:"
	@TEST_FILTER='test_watertight_triangles*' $(BUILD)/fp-contract/tests/test_ch01 | grep -E 'leak|OK|FAILED'

# Chapter 06's wide BVH with 8 children per node instead of 4 (BVH4_WIDTH,
# bvh4.h): its tests, built in a build directory of their own, so that the
# other width keeps working. Compare speeds with
# $(BUILD)/bvh8/bin/bench_accel beside $(BUILD)/bin/bench_accel.
.PHONY: test-bvh8
test-bvh8:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/bvh8 CFLAGS="$(OPT) -g -DBVH4_WIDTH=8" \
	  $(BUILD)/bvh8/tests/test_ch13 $(BUILD)/bvh8/bin/bench_accel >/dev/null
	@$(BUILD)/bvh8/tests/test_ch13

# ---------------------------------------------------------------- benchmarks --
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
# same path tracer on Embree's kernels.
bench: $(BUILD)/bin/bench_accel $(BUILD)/bin/13-production
	@mkdir -p $(BUILD)/data
	@if [ -f $(SHARED)/anchors/embree_bench.c ]; then \
	  $(MAKE) --no-print-directory $(BUILD)/bin/embree_bench && \
	  rm -f $(BUILD)/data/embree.txt && \
	  for n in $(BENCH_SIZES); do \
	    $(BUILD)/bin/embree_bench embree $$n medium 1 $(BENCH_REPS) | tee -a $(BUILD)/data/embree.txt; \
	  done; \
	else echo "no $(SHARED)/anchors/embree_bench.c: timing without Embree"; fi
	$(BUILD)/bin/bench_accel --sizes $(subst $(space),$(comma),$(strip $(BENCH_SIZES))) --reps $(BENCH_REPS) \
	  --out $(BUILD)/data/accel.csv --stadium $(BUILD)/data/stadium.csv $(if $(wildcard $(SHARED)/anchors/embree_bench.c),--embree $(BUILD)/data/embree.txt)
	$(BUILD)/bin/13-production --bench --width 256 --spp 16 --bench-csv $(BUILD)/data/ch13_speed.csv
	@if [ -n "$(EMBREE_HEADER)" ]; then \
	  $(MAKE) --no-print-directory $(BUILD)/bin/bench_pt_embree && \
	  echo "$(BUILD)/bin/bench_pt_embree --width 256 --spp 16 --data $(BUILD)/data" && \
	  $(BUILD)/bin/bench_pt_embree --width 256 --spp 16 --data $(BUILD)/data; \
	else echo "no Embree header (make bench-deps): the path tracer on Embree skipped"; fi

# ---------------------------------------------------------------- plots --
# Every figure is drawn by a gnuplot script in plots/ from CSV that a program
# wrote under build/data/: plots/chNN_*.gp from chapter NN's program run with
# --data, plots/accel_*.gp from the benchmark.
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

bench-deps:
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="libembree-dev"

# ---------------------------------------------------------------- the book --
# `make docs` weaves each chapter's README.md into build/docs/NN-name.html
# with pandoc and the Lua filter docs/weave.lua: code excerpts are read from
# the sources now, images are the ones the programs and `make plots` make
# (each shown with its command, from docs/figures.txt), formulas become
# MathML, and there are no scripts. docs/coverage.md maps every concept of
# lectures 13-16 to its file, function, test and figure; the filter fails
# the build if any of them does not exist. `make test-docs` opens every page
# in headless Chromium and checks images, links and math.
DOCS := $(BUILD)/docs
DOCS_TEST := $(BUILD)/docs-test
DOC_NOTES := scene-format hard-cases
DOC_PAGES := $(patsubst %,$(DOCS)/%.html,$(CHAPTERS)) $(DOCS)/index.html $(DOCS)/coverage.html \
  $(patsubst %,$(DOCS)/%.html,$(DOC_NOTES))
DOC_FIGURES := $(patsubst %,$(BUILD)/%,$(shell sed -n 's|^\(out/[^ ]*\.png\).*|\1|p' docs/figures.txt))
DOC_PLOTS_STAMP := $(BUILD)/plots/.made
DOC_SOURCES := $(wildcard common/*.[ch] chapters/*/*.[ch] tests/*.c)
DOC_INPUTS := docs/weave.lua docs/template.html docs/lectures.md docs/figures.txt $(DOC_SOURCES)
DOC_ROOT = $(shell realpath -m --relative-to=$(DOCS) .)
DOC_PANDOC = pandoc --fail-if-warnings --mathml --standalone --template docs/template.html \
  --lua-filter docs/weave.lua -M chapters="$(CHAPTERS)" -M build=$(BUILD) -M docs=$(DOCS) \
  -M root=$(DOC_ROOT) -M figures=docs/figures.txt -M lectures=docs/lectures.md -M plots="$(PLOT_SCRIPTS)"
# $(call docs_check,DIR,PAGES): tests/docs_check.html's report on DIR's pages (comma-separated).
docs_check = $(CHROMIUM) --allow-file-access-from-files --virtual-time-budget=60000 --dump-dom \
  "file://$(abspath tests/docs_check.html)?dir=file://$(1)/&pages=$(2)" 2>> $(DOCS_TEST)/chromium.log \
  | sed -n '/<pre id="report">/,/<\/pre>/p' | sed 's/<[^>]*>//g; /^$$/d'
CHROMIUM = chromium --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --user-data-dir=$(abspath $(DOCS_TEST))/profile

docs: $(DOC_PAGES)
	@echo "The book is in $(DOCS)/: open $(DOCS)/index.html"

# Each figure by the command docs/figures.txt gives it (build/ there means $(BUILD)).
$(DOC_FIGURES): $(BUILD)/%.png: docs/figures.txt $(PROGRAMS) $(DOC_PROGRAMS)
	@mkdir -p $(dir $@)
	@cmd=$$(awk -v f='$*.png' '$$1 == f { $$1 = ""; print }' docs/figures.txt | sed 's|build/|$(BUILD)/|g'); \
	echo "$$cmd"; $$cmd --quiet

$(DOC_PLOTS_STAMP): $(PLOT_SCRIPTS) $(PROGRAMS)
	@$(MAKE) --no-print-directory plots
	@touch $@

$(DOCS)/book.css: docs/book.css | docs-deps
	@mkdir -p $(DOCS)/img
	cp $< $@

$(DOCS)/%.html: chapters/%/README.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOC_PLOTS_STAMP) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm -M page=chapter -M chapter=$* -M files="$(notdir $(wildcard chapters/$*/*.[ch]))" $< -o $@

# The index shows each chapter's picture: it waits for them (with -j, it
# was made before them and refused, naming the missing images).
$(DOCS)/index.html: docs/index.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm -M page=index -M chapter= $< -o $@

# The notes beside the chapters: the scene format and the hard-case catalog.
$(patsubst %,$(DOCS)/%.html,$(DOC_NOTES)): $(DOCS)/%.html: docs/%.md $(DOC_INPUTS) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm -M page=note -M chapter= $< -o $@

$(DOCS)/coverage.html: docs/coverage.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOC_PLOTS_STAMP) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm -M page=coverage -M chapter= $< -o $@

# The checks fail when they should: a coverage row naming a function that
# does not exist, an excerpt whose function is gone (each must name its file
# and line); then every page in Chromium, through tests/docs_check.html, which
# loads each page in a frame and reports what is broken; then a screenshot of
# the index ($(DOCS)/index-screenshot.png) to look at.
test-docs: docs | docs-deps
	@mkdir -p $(DOCS_TEST)
	@for bad in tests/docs/bad_*.md; do \
	  want=$$(sed -n 's/^<!-- expect: \(.*\) -->$$/\1/p' $$bad); \
	  if $(DOC_PANDOC) -f gfm -M page=$$(sed -n 's/^<!-- page: \(.*\) -->$$/\1/p' $$bad) -M chapter= \
	       $$bad -o $(DOCS_TEST)/bad.html 2> $(DOCS_TEST)/bad.log; then \
	    echo "FAIL: $$bad was accepted"; exit 1; fi; \
	  grep -qF "$$want" $(DOCS_TEST)/bad.log || { cat $(DOCS_TEST)/bad.log; echo "FAIL: $$bad: no '$$want'"; exit 1; }; \
	  echo "ok: $$bad is refused: $$want"; \
	done
	@$(call docs_check,$(abspath tests/docs),bad_page.html) > $(DOCS_TEST)/bad_page.txt; \
	grep -q '^RESULT: FAIL (1 pages, 3 problems)' $(DOCS_TEST)/bad_page.txt \
	  || { cat $(DOCS_TEST)/bad_page.txt; echo "FAIL: the browser check missed a fault of tests/docs/bad_page.html"; exit 1; }; \
	echo "ok: the browser check finds the three faults of tests/docs/bad_page.html"
	@pages=$$(cd $(DOCS) && ls *.html | tr '\n' ',' | sed 's/,$$//'); \
	$(call docs_check,$(abspath $(DOCS)),$$pages) > $(DOCS_TEST)/report.txt; \
	cat $(DOCS_TEST)/report.txt; grep -q '^RESULT: PASS' $(DOCS_TEST)/report.txt
	@$(CHROMIUM) --window-size=1100,1500 --screenshot=$(abspath $(DOCS))/index-screenshot.png \
	  file://$(abspath $(DOCS))/index.html 2>> $(DOCS_TEST)/chromium.log
	@echo "test-docs: every page checked; screenshot of the index: $(DOCS)/index-screenshot.png"

docs-deps:
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="pandoc chromium"

# ---------------------------------------------------------------- valgrind --
# One small render of every chapter program under valgrind: no invalid reads
# or writes, no definite leaks. (OpenMP's thread pool keeps its stacks until
# exit, which valgrind calls "possibly lost"; those are not ours.)
# Each chapter's own flags keep its run short: small procedural meshes (04-06),
# few furnace bounces (07), the quick experiment (08), one sample (09).
VALGRIND_ARGS_01 :=
VALGRIND_ARGS_02 :=
VALGRIND_ARGS_03 :=
VALGRIND_ARGS_04 := --triangles 1024 --probe-rays 100
VALGRIND_ARGS_05 := --triangles 1024
VALGRIND_ARGS_06 := --triangles 1024
VALGRIND_ARGS_07 := --bounces 3
VALGRIND_ARGS_08 := --quick --runs 8 --max-log2n 6
VALGRIND_ARGS_09 := --spp 1 --max-depth 4
VALGRIND_ARGS_10 := --spp 1 --max-depth 2 --light-samples 1 --glossy-samples 2
VALGRIND_ARGS_11 := --spp 1 --max-depth 3
VALGRIND_ARGS_12 := --spp 2 --max-depth 3 --bootstrap 1000 --chains 8
valgrind: $(PROGRAMS) | valgrind-deps
	@mkdir -p $(BUILD)/valgrind
	@for c in $(CHAPTERS); do \
	  n=$${c%%-*}; \
	  case $$n in 01) a="$(VALGRIND_ARGS_01)";; 02) a="$(VALGRIND_ARGS_02)";; 03) a="$(VALGRIND_ARGS_03)";; \
	    04) a="$(VALGRIND_ARGS_04)";; 05) a="$(VALGRIND_ARGS_05)";; 06) a="$(VALGRIND_ARGS_06)";; \
	    07) a="$(VALGRIND_ARGS_07)";; 08) a="$(VALGRIND_ARGS_08)";; 09) a="$(VALGRIND_ARGS_09)";; \
	    10) a="$(VALGRIND_ARGS_10)";; 11) a="$(VALGRIND_ARGS_11)";; 12) a="$(VALGRIND_ARGS_12)";; *) a="";; esac; \
	  echo "valgrind $(BUILD)/bin/$$c $$a"; \
	  valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite --show-possibly-lost=no \
	    $(BUILD)/bin/$$c --width 32 --height 24 --threads 2 --quiet $$a --out $(BUILD)/valgrind/$$c.exr || exit 1; \
	done; echo "valgrind: no errors and no definite leaks in $(words $(CHAPTERS)) programs"

valgrind-deps:
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="valgrind"

# ---------------------------------------------------------------- fuzzing --
# One libFuzzer target per parser (tests/fuzz_NAME.c), built with clang and
# the address and undefined-behaviour sanitizers, run for FUZZ_SECONDS each
# from the seed corpus tests/fuzz/NAME/.
FUZZ_SECONDS ?= 30
FUZZ_TARGETS := $(patsubst tests/fuzz_%.c,%,$(sort $(wildcard tests/fuzz_*.c)))

$(BUILD)/fuzz/fuzz_%: tests/fuzz_%.c $(COMMON_SRC) | fuzz-deps
	@mkdir -p $(dir $@)
	clang -std=c11 -D_DEFAULT_SOURCE -g -O1 -ffp-contract=off -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	  $(CPPFLAGS) $^ -o $@ $(LDLIBS)

fuzz: $(foreach t,$(FUZZ_TARGETS),$(BUILD)/fuzz/fuzz_$(t))
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(BUILD)/fuzz/corpus_$$t; \
	  echo "fuzzing $$t for $(FUZZ_SECONDS) s (seed corpus tests/fuzz/$$t/)"; \
	  $(BUILD)/fuzz/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 \
	    $(BUILD)/fuzz/corpus_$$t tests/fuzz/$$t > $(BUILD)/fuzz/$$t.log 2>&1 \
	    || { tail -40 $(BUILD)/fuzz/$$t.log; echo "fuzz_$$t FOUND A CRASH (input saved in the current directory)"; exit 1; }; \
	  runs=$$(sed -n 's/^stat::number_of_executed_units: *//p' $(BUILD)/fuzz/$$t.log); \
	  echo "fuzz_$$t: $$runs inputs, no crash"; \
	done

fuzz-deps:
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="clang libclang-rt-14-dev"

# Installs what is missing, by Debian package name, and says what it installed.
deps:
	@if ! command -v dpkg-query >/dev/null 2>&1; then \
	  echo "note: not a Debian system; make sure these are installed: $(DEBIAN_PACKAGES)"; exit 0; fi; \
	missing=""; \
	for p in $(DEBIAN_PACKAGES); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q ' installed$$' || missing="$$missing $$p"; \
	done; \
	[ -z "$$missing" ] && exit 0; \
	sudo=""; [ "$$(id -u)" = 0 ] || sudo=sudo; \
	echo "installing Debian packages:$$missing"; \
	$$sudo apt-get update -qq && \
	DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y -qq --no-install-recommends $$missing >/dev/null && \
	echo "installed:$$missing"

help:
	@sed -n '3,16p' Makefile | sed 's/^# \{0,1\}//'
	@echo "chapters: $(CHAPTERS)"

clean:
	rm -rf $(BUILD)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
