# libFuzzer targets (tests/fuzz/fuzz_*.c), built with clang under ASan+UBSan.
#
#   make fuzz                 every target for FUZZ_TIME s (default 60) in turn,
#                             new inputs kept in $(BUILD)/fuzz/corpus/<target>
#   make fuzz FUZZ_TARGETS=fuzz_ops FUZZ_TIME=600   one target, longer
#   make fuzz-ci              replay the committed corpora, then every target
#                             for FUZZ_CI_TIME s (>= 60), FUZZ_JOBS at a time
#   make fuzz-build           just build them
#
# Seeds: tests/fuzz/corpus/<target>/; dictionary: tests/fuzz/<target>.dict.
# A crash leaves its input in $(BUILD)/fuzz/artifacts/; replay it with
# $(BUILD)/fuzz/<target> <file>. The code under test is compiled again here
# (not the gcc objects of `make`), with -fsanitize=fuzzer-no-link.

FUZZ_CC ?= clang
FUZZ_TIME ?= 60
FUZZ_CI_TIME ?= 60
FUZZ_JOBS ?= 2
FUZZ_BUILD := $(BUILD)/fuzz
FUZZ_SAN := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
FUZZ_CFLAGS := -std=c11 -g -O1 -I. -D_GNU_SOURCE -MMD -MP $(FUZZ_SAN) -fsanitize=fuzzer-no-link \
	-Wall -Wextra
# hal/linux/backend_cfg.c: the <backends> section's handler, read by the same
# reader as the rest of the vehicle file (fuzz_config).
FUZZ_SUT_SRC := $(FW_SRC) $(PROTO_SRC) $(HOST_SRC) $(SIM_SRC) hal/linux/backend_cfg.c \
	$(wildcard tests/model/*.c)
FUZZ_EVDEV := -I/usr/include/libevdev-1.0
FUZZ_ALL := $(patsubst tests/fuzz/%.c,%,$(wildcard tests/fuzz/fuzz_*.c))
FUZZ_TARGETS ?= $(FUZZ_ALL)
FUZZ_BINS := $(addprefix $(FUZZ_BUILD)/,$(FUZZ_ALL))
# libFuzzer options shared by every run: a hang is a finding (10 s per input).
# FUZZ_SEED=N makes a run repeatable (CI uses one); 0 lets libFuzzer pick.
FUZZ_SEED ?= 0
FUZZ_OPTS := -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 -seed=$(FUZZ_SEED)

# fuzz-run-* must not be .PHONY: make skips pattern rules for phony targets
# (they would silently do nothing); FORCE makes them run every time instead.
.PHONY: fuzz fuzz-build fuzz-ci fuzz-replay FORCE
FORCE:

$(FUZZ_BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  FUZZCC  $<")
	$(Q)$(FUZZ_CC) $(FUZZ_CFLAGS) $(if $(filter tests/fuzz/%,$<),-Werror) \
		$(if $(filter hal/linux/%,$<),$(FUZZ_EVDEV)) -c $< -o $@

$(FUZZ_BUILD)/libsut.a: $(patsubst %.c,$(FUZZ_BUILD)/obj/%.o,$(FUZZ_SUT_SRC))
	@$(if $(Q),echo "  AR      $@")
	$(Q)rm -f $@ && $(AR) rcs $@ $^

$(FUZZ_BUILD)/fuzz_%: $(FUZZ_BUILD)/obj/tests/fuzz/fuzz_%.o $(FUZZ_BUILD)/libsut.a
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(FUZZ_CC) $(FUZZ_SAN) -fsanitize=fuzzer -o $@ $^ $(LDLIBS_HOST) -levdev

fuzz-build: $(FUZZ_BINS)

# One target for $(FUZZ_RUN_TIME) s, seeds read-only, new inputs to the work corpus.
fuzz-run-%: $(FUZZ_BUILD)/% FORCE
	@mkdir -p $(FUZZ_BUILD)/corpus/$* $(FUZZ_BUILD)/artifacts
	@echo "  FUZZ    $* for $(FUZZ_RUN_TIME) s"
	$(Q)$(FUZZ_BUILD)/$* $(FUZZ_OPTS) -max_total_time=$(FUZZ_RUN_TIME) \
		$(if $(wildcard tests/fuzz/$*.dict),-dict=tests/fuzz/$*.dict) \
		-artifact_prefix=$(FUZZ_BUILD)/artifacts/$*- \
		$(FUZZ_BUILD)/corpus/$* tests/fuzz/corpus/$* > $(FUZZ_BUILD)/$*.log 2>&1 \
		|| { tail -n 60 $(FUZZ_BUILD)/$*.log; exit 1; }
	@grep -h "stat::number_of_executed_units\|stat::peak_rss_mb" $(FUZZ_BUILD)/$*.log \
		| sed 's/^/  $* /'

fuzz: $(addprefix $(FUZZ_BUILD)/,$(FUZZ_TARGETS))
	$(Q)for t in $(FUZZ_TARGETS); do \
		$(MAKE) --no-print-directory fuzz-run-$$t FUZZ_RUN_TIME=$(FUZZ_TIME) || exit 1; \
	done

# Every committed corpus input once (a regression test of past findings).
# A long run that anyone can start (CI keeps its short fixed-seed run):
#   make fuzz-long [FUZZ_LONG_TARGETS=fuzz_ops] [FUZZ_LONG_TIME=1800] [FUZZ_SEED=N]
# FUZZ_SEED=0 (the default) lets libFuzzer pick a seed and print it.
FUZZ_LONG_TIME ?= 1800
FUZZ_LONG_TARGETS ?= fuzz_ops
.PHONY: fuzz-long
fuzz-long:
	$(Q)$(MAKE) --no-print-directory fuzz FUZZ_TARGETS="$(FUZZ_LONG_TARGETS)" \
		FUZZ_TIME=$(FUZZ_LONG_TIME)

fuzz-replay: $(FUZZ_BINS)
	$(Q)for t in $(FUZZ_ALL); do \
		echo "  REPLAY  $$t ($$(ls tests/fuzz/corpus/$$t | wc -l) inputs)"; \
		$(FUZZ_BUILD)/$$t -runs=0 tests/fuzz/corpus/$$t > $(FUZZ_BUILD)/$$t.replay.log 2>&1 \
			|| { tail -n 60 $(FUZZ_BUILD)/$$t.replay.log; exit 1; }; \
	done

fuzz-ci: fuzz-replay
	$(Q)$(MAKE) --no-print-directory -j$(FUZZ_JOBS) FUZZ_RUN_TIME=$(FUZZ_CI_TIME) \
		$(addprefix fuzz-run-,$(FUZZ_ALL))

-include $(shell find $(FUZZ_BUILD)/obj -name '*.d' 2>/dev/null)
