# `make docs` weaves each chapter's README.md into build/docs/NN-name.html
# with pandoc and the Lua filter docs/weave.lua: code excerpts are read from
# the sources now, images are the ones the programs and `make plots` make
# (each shown with its command, from docs/figures.txt), formulas become
# MathML, and the one script is inline (chapter 09's clickable picture:
# docs/path_explorer.js over build/data/ch09_paths.json). docs/coverage.md maps every concept of
# lectures 13-16 to its file, function, test and figure; the filter fails
# the build if any of them does not exist. `make test-docs` opens every page
# in headless Chromium and checks images, links and math, that each chapter
# prints on at most DOC_MAX_PRINTED pages, and that every image a README
# shows is a file of the repository, and that no chapter quotes a time
# typed by hand (tests/check_measured_numbers.sh); each check first refuses its bad
# input in tests/docs/.
#
# `make excerpts` writes the code of every excerpt in the READMEs again from
# the sources (docs/excerpts.sh), so that a README shows its code on any Git
# host; it writes only what changed, and after a merge one run brings every
# README back in line. tests/check_excerpts.sh (in make test and test-docs)
# fails, naming the README's line and the function, where they differ.

.PHONY: docs docs-deps test-docs figures excerpts

DOCS := $(BUILD)/docs
DOCS_TEST := $(BUILD)/docs-test
DOC_NOTES := scene-format hard-cases
# A chapter's companion pages (its going-further.md, chapter 13's
# what-did-not-pay.md): woven beside it as NN-name.going-further.html.
DOC_COMPANIONS := $(filter-out %/README.md,$(wildcard chapters/*/*.md))
companion_page = $(DOCS)/$(subst /,.,$(patsubst chapters/%.md,%,$(1))).html
DOC_PAGES := $(patsubst %,$(DOCS)/%.html,$(CHAPTERS)) $(DOCS)/index.html $(DOCS)/coverage.html \
  $(patsubst %,$(DOCS)/%.html,$(DOC_NOTES)) $(foreach f,$(DOC_COMPANIONS),$(call companion_page,$(f)))
DOC_FIGURES := $(patsubst %,$(BUILD)/%,$(shell sed -n 's|^\(out/[^ ]*\.png\).*|\1|p' docs/figures.txt))
# one stamp per mode: make docs FULL=1 after make docs redraws from full data
DOC_PLOTS_STAMP := $(BUILD)/plots/.made-$(PLOT_MODE)
DOC_SOURCES := $(wildcard common/*/*.[ch] chapters/*/*.[ch] tests/*.c)
DOC_INPUTS := docs/weave.lua docs/template.html docs/lectures.md docs/figures.txt docs/path_explorer.js $(DOC_SOURCES) $(wildcard docs/diagrams/*.svg)
# The chapters whose slides draw their geometry: each page shows at least one
# diagram of it (docs/diagrams/*.svg), or the weave stops.
# A chapter page prints on at most this many pages of A4 (make test-docs).
DOC_MAX_PRINTED := 20
DIAGRAM_CHAPTERS := 01 02 03 04 05 06 07 08 09 10 11 12
DOC_ROOT = $(shell realpath -m --relative-to=$(DOCS) .)
DOC_PANDOC = pandoc --fail-if-warnings --mathml --standalone --template docs/template.html \
  --lua-filter docs/weave.lua -M chapters="$(CHAPTERS)" -M build=$(BUILD) -M docs=$(DOCS) \
  -M root=$(DOC_ROOT) -M figures=docs/figures.txt -M lectures=docs/lectures.md -M plots="$(PLOT_SCRIPTS)" \
  -M diagrams="$(DIAGRAM_CHAPTERS)"
# $(call docs_check,DIR,PAGES): tests/docs_check.html's report on DIR's pages (comma-separated).
docs_check = $(CHROMIUM) --allow-file-access-from-files --virtual-time-budget=60000 --dump-dom \
  "file://$(abspath tests/docs_check.html)?dir=file://$(1)/&pages=$(2)" 2>> $(DOCS_TEST)/chromium.log \
  | sed -n '/<pre id="report">/,/<\/pre>/p' | sed 's/<[^>]*>//g; /^$$/d'
CHROMIUM = chromium --headless --no-sandbox --disable-gpu --hide-scrollbars \
  --user-data-dir=$(abspath $(DOCS_TEST))/profile

docs: $(DOC_PAGES)
	@echo "The book is in $(DOCS)/: open $(DOCS)/index.html"

DOC_MARKDOWN = README.md docs/*.md chapters/*/*.md
excerpts:
	@docs/excerpts.sh $(DOC_MARKDOWN)

# make figures: the committed copies in docs/img/ of every figure a page
# shows (the READMEs link them, so that they read with their pictures on any
# Git host, without a build): each made again from the build's own (the
# program's picture, or the plot, from the data `make plots` has: quick, or
# FULL=1), renders shrunk to at most FIGURE_WIDTH pixels wide, plots and strips
# of small renders side by side (*_strip.png: their panels are small already)
# to PLOT_WIDTH.
# docs/img/SOURCES says where each copy came from and how its data was made.
FIGURE_WIDTH ?= 320
PLOT_WIDTH ?= 800
COMMITTED_FIGURES := $(sort $(patsubst %,docs/img/%,$(notdir $(shell grep -ho 'img/[A-Za-z0-9_]*\.png' \
  chapters/*/*.md docs/index.md README.md))))
COMMITTED_TABLES := $(sort $(shell sed -n 's/^<!-- table \([a-z0-9_]*\) -->$$/\1/p' \
  chapters/*/*.md docs/*.md README.md))
figures: $(DOC_FIGURES) $(DOC_PLOTS_STAMP) $(BUILD)/bin/png_shrink
	@mkdir -p docs/img
	@printf '# The committed copies of the figures (make figures): file, source, how its data was made.\n' \
	  > docs/img/SOURCES.tmp
	@for f in $(notdir $(COMMITTED_FIGURES)); do \
	  if grep -q "^out/$$f " docs/figures.txt; then \
	    src=out/$$f; width=$(FIGURE_WIDTH); \
	    case $$f in *_strip.png) width=$(PLOT_WIDTH);; esac; \
	    run="rendered (at most $$width px wide here)"; \
	  else \
	    src=plots/$$f; width=$(PLOT_WIDTH); n=$$(echo $$f | sed -n 's/^ch\([0-9][0-9]\)_.*/\1/p'); \
	    rec=accel; [ -z "$$n" ] || rec=ch$$n; \
	    run="$$(cut -f1 $(BUILD)/data/$$rec.run 2>/dev/null || echo full) data"; \
	  fi; \
	  $(BUILD)/bin/png_shrink $(BUILD)/$$src docs/img/$$f.tmp $$width && mv docs/img/$$f.tmp docs/img/$$f || exit 1; \
	  printf '%s\tbuild/%s\t%s\n' $$f $$src "$$run" >> docs/img/SOURCES.tmp; \
	done
	@mv docs/img/SOURCES.tmp docs/img/SOURCES
	@for t in $(COMMITTED_TABLES); do cp $(BUILD)/plots/$$t.md docs/img/$$t.md || exit 1; done
	@docs/splice.sh docs/img README.md docs/*.md chapters/*/*.md
	@du -ch docs/img/*.png | tail -1 | sed 's|$$| in docs/img/ (commit them)|'

# Chapter 09's clickable picture: the paths of 16 x 16 of its pixels, one
# sample each, from the program's --explain, as JSON (a few seconds).
DOC_PATHS := $(BUILD)/data/ch09_paths.json
$(DOC_PATHS): $(BUILD)/bin/09-path-tracing docs/figures/explain_paths.py
	@mkdir -p $(dir $@)
	python3 docs/figures/explain_paths.py $(BUILD)/bin/09-path-tracing 16 $@

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

$(DOCS)/%.html: chapters/%/README.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOC_PLOTS_STAMP) $(wildcard $(BUILD)/plots/*.md) $(DOCS)/book.css $(DOC_PATHS)
	$(DOC_PANDOC) -f gfm+tex_math_dollars -M page=chapter -M chapter=$* -M files="$(notdir $(wildcard chapters/$*/*.[ch]))" $< -o $@

# The index shows each chapter's picture: it waits for them (with -j, it
# was made before them and refused, naming the missing images).
$(DOCS)/index.html: docs/index.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm+tex_math_dollars -M page=index -M chapter= $< -o $@

# The notes beside the chapters: the scene format and the hard-case catalog.
$(patsubst %,$(DOCS)/%.html,$(DOC_NOTES)): $(DOCS)/%.html: docs/%.md $(DOC_INPUTS) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm+tex_math_dollars -M page=note -M chapter= $< -o $@

# The companion pages: their measured tables and figures too.
define companion_rule
$(call companion_page,$(1)): $(1) $$(DOC_INPUTS) $$(DOC_FIGURES) $$(DOC_PLOTS_STAMP) $$(wildcard $$(BUILD)/plots/*.md) $$(DOCS)/book.css
	$$(DOC_PANDOC) -f gfm+tex_math_dollars -M page=note -M chapter= $$< -o $$@
endef
$(foreach f,$(DOC_COMPANIONS),$(eval $(call companion_rule,$(f))))

$(DOCS)/coverage.html: docs/coverage.md $(DOC_INPUTS) $(DOC_FIGURES) $(DOC_PLOTS_STAMP) $(DOCS)/book.css
	$(DOC_PANDOC) -f gfm+tex_math_dollars -M page=coverage -M chapter= $< -o $@

# The checks fail when they should: a coverage row naming a function that
# does not exist, an excerpt whose function is gone (each must name its file
# and line); then every page in Chromium, through tests/docs_check.html, which
# loads each page in a frame and reports what is broken; then a screenshot of
# the index ($(DOCS)/index-screenshot.png) to look at.
test-docs: docs | docs-deps
	@mkdir -p $(DOCS_TEST)
	@for bad in tests/docs/bad_*.md; do \
	  want=$$(sed -n 's/^<!-- expect: \(.*\) -->$$/\1/p' $$bad); \
	  if $(DOC_PANDOC) -f gfm+tex_math_dollars -M page=$$(sed -n 's/^<!-- page: \(.*\) -->$$/\1/p' $$bad) \
	       -M chapter=$$(sed -n 's/^<!-- chapter: \(.*\) -->$$/\1/p' $$bad) \
	       $$bad -o $(DOCS_TEST)/bad.html 2> $(DOCS_TEST)/bad.log; then \
	    echo "FAIL: $$bad was accepted"; exit 1; fi; \
	  grep -qF "$$want" $(DOCS_TEST)/bad.log || { cat $(DOCS_TEST)/bad.log; echo "FAIL: $$bad: no '$$want'"; exit 1; }; \
	  echo "ok: $$bad is refused: $$want"; \
	done
	@$(call docs_check,$(abspath tests/docs),bad_page.html) > $(DOCS_TEST)/bad_page.txt; \
	grep -q '^RESULT: FAIL (1 pages, 5 problems)' $(DOCS_TEST)/bad_page.txt \
	  || { cat $(DOCS_TEST)/bad_page.txt; echo "FAIL: the browser check missed a fault of tests/docs/bad_page.html"; exit 1; }; \
	echo "ok: the browser check finds the five faults of tests/docs/bad_page.html (one: a clickable picture drawing too few segments)"
	@! tests/check_images.sh tests/docs/bad_missing_image.md > $(DOCS_TEST)/bad_images.txt \
	  || { echo "FAIL: tests/check_images.sh accepted tests/docs/bad_missing_image.md"; exit 1; }; \
	grep -q 'no_such_figure.png does not exist' $(DOCS_TEST)/bad_images.txt || { cat $(DOCS_TEST)/bad_images.txt; exit 1; }; \
	echo "ok: tests/docs/bad_missing_image.md is refused: its image is not in the repository"
	@cp tests/docs/hand_edited_table.md $(DOCS_TEST)/hand_edited_table.md; \
	! docs/splice.sh --check docs/img $(DOCS_TEST)/hand_edited_table.md > $(DOCS_TEST)/hand_edited_table.txt \
	  || { echo "FAIL: a table edited by hand (tests/docs/hand_edited_table.md) passed the check"; exit 1; }; \
	echo "ok: tests/docs/hand_edited_table.md is refused: its table is not the one its run wrote"
	@docs/splice.sh --check docs/img README.md docs/*.md chapters/*/*.md \
	  && echo "ok: every measured table a README quotes is the one the run that drew its figure wrote"
	@tests/check_excerpts.sh $(BUILD)
	@tests/check_measured_numbers.sh chapters/*/*.md
	@tests/check_images.sh README.md docs/*.md chapters/*/*.md \
	  && echo "ok: every image the READMEs and pages show is a file of the repository"
	@! CHROMIUM="$(CHROMIUM)" tests/docs_print_pages.sh $(DOC_MAX_PRINTED) tests/docs/bad_long_page.html \
	  > $(DOCS_TEST)/bad_print.txt || { echo "FAIL: tests/docs/bad_long_page.html passed the print check"; exit 1; }; \
	grep -q '^FAIL.*more than $(DOC_MAX_PRINTED)' $(DOCS_TEST)/bad_print.txt || { cat $(DOCS_TEST)/bad_print.txt; exit 1; }; \
	echo "ok: $$(cat $(DOCS_TEST)/bad_print.txt | sed 's/^FAIL //')"
	@CHROMIUM="$(CHROMIUM)" tests/docs_print_pages.sh $(DOC_MAX_PRINTED) $(patsubst %,$(DOCS)/%.html,$(CHAPTERS)) \
	  | tee $(DOCS_TEST)/print.txt | tr '\n' ' ' | sed 's/ $$/\n/'; \
	! grep -q '^FAIL' $(DOCS_TEST)/print.txt
	@pages=$$(cd $(DOCS) && ls *.html | tr '\n' ',' | sed 's/,$$//'); \
	$(call docs_check,$(abspath $(DOCS)),$$pages) > $(DOCS_TEST)/report.txt; \
	cat $(DOCS_TEST)/report.txt; grep -q '^RESULT: PASS' $(DOCS_TEST)/report.txt; \
	grep -q '^09-path-tracing.html: path explorer: clicked pixel' $(DOCS_TEST)/report.txt \
	  || { echo "FAIL: the browser check did not click chapter 09's picture"; exit 1; }
	@$(CHROMIUM) --window-size=1100,1500 --screenshot=$(abspath $(DOCS))/index-screenshot.png \
	  file://$(abspath $(DOCS))/index.html 2>> $(DOCS_TEST)/chromium.log
	@echo "test-docs: every page checked; screenshot of the index: $(DOCS)/index-screenshot.png"

docs-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="pandoc chromium"
