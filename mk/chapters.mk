# The chapters: common/'s library, then for every chapters/NN-name/ its
# library, its program, its cmocka suite (tests/test_chNN.c) and the targets
# chNN and test-chNN. Nothing here names a chapter: a new directory
# chapters/NN-name/ (with tests/test_chNN.c) gets all of them as it is.

.PHONY: all demo

COMMON_SRC := $(sort $(wildcard common/core/*.c common/program/*.c))
CHAPTERS := $(sort $(notdir $(wildcard chapters/[0-9][0-9]-*)))
chapter_number = $(firstword $(subst -, ,$(1)))

obj = $(patsubst %.c,$(BUILD)/obj/%.o,$(1))
COMMON_LIB := $(BUILD)/lib/libcommon.a

# The core sees its own headers only (mk/config.mk).
$(BUILD)/obj/common/core/%.o: COMMON_INCLUDES = -Icommon/core

$(BUILD)/obj/%.o: %.c | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(CPPFLAGS) -c $< -o $@

# The project's version (git describe) as a C string, for the records every
# program writes beside its image (common/program/program.c). The file is rewritten
# only when the version changes, so a build after a commit relinks, and a
# build without one compiles nothing. Outside a git checkout: "unknown".
VERSION_SRC := $(BUILD)/gen/version.c
.PHONY: version-check
$(VERSION_SRC): version-check
	@mkdir -p $(dir $@)
	@v=$$(git describe --always --dirty 2>/dev/null || echo unknown); \
	printf '/* made by mk/chapters.mk */\nconst char *const PROJECT_VERSION = "%s";\n' "$$v" > $@.tmp; \
	if cmp -s $@.tmp $@; then rm -f $@.tmp; else mv $@.tmp $@; fi

$(BUILD)/obj/$(BUILD)/gen/version.o: $(VERSION_SRC) | deps
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(CPPFLAGS) -c $< -o $@

$(COMMON_LIB): $(call obj,$(COMMON_SRC)) $(BUILD)/obj/$(BUILD)/gen/version.o
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
	@if [ -d .exercises ]; then $$(EXERCISE_TOOL) picture $$($(1)_NUM) --build $(BUILD) -- --out $(BUILD)/out/ch$$($(1)_NUM).exr $$(ARGS); fi

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

all: $(PROGRAMS) $(TESTS) $(DOC_PROGRAMS) $(BUILD)/bin/image_compare
	@mkdir -p $(BUILD)/out

demo: $(PROGRAMS)
	@$(MAKE) --no-print-directory $(DEMOS)
	@echo "Images are in $(BUILD)/out/: open the .png previews, or the .exr files in an EXR viewer."

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
