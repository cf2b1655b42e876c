# Static analysis: `make lint` must end with zero findings.
#
#   cppcheck    warning, style, performance, portability on firmware/, proto/,
#               hal/, host_sim/; suppressions with reasons in
#               tools/lint/cppcheck.supp
#   clang-tidy  the checks of .clang-tidy (reasons there), warnings as errors
#   clang       -Wconversion -Wshadow -Wsign-conversion -Werror on firmware/ and
#               proto/ (the gcc build enforces the same; clang sees more)
#   clang-format every tracked C file follows .clang-format (`make format` fixes)
#   client      vehiclectl links no firmware object (nm): the client library
#               uses the command table and the encodings, never the unit
#   fnsize      no function of firmware/ over 80 body lines or nested deeper
#               than 4 (tools/lint/fnsize.py)
# tests/ are excluded from the analysers (cmocka macros); they build with
# -Wall -Wextra -Werror.
# Also in the set: hal/linux/ (the vehicle-fw backends, mk/linux.mk), its
# drive and joystick simulators, and the programs' mains in tools/. Not yet:
# hal/cortexm/ (it needs the ARM target) and tools/bench/, tools/ref/.

LINT_SRC := $(FW_SRC) $(PROTO_SRC) $(HOST_SRC) $(SIM_SRC) $(wildcard host_sim/*_main.c) \
	$(wildcard hal/linux/*.c hal/linux/sim/*.c tools/*.c)
LINT_DEFS := -std=c11 -I. -D_GNU_SOURCE -I/usr/include/libevdev-1.0
CLANG ?= clang

.PHONY: lint lint-cppcheck lint-tidy lint-warnings lint-format lint-client lint-fnsize

lint: lint-format lint-cppcheck lint-warnings lint-tidy lint-client lint-fnsize

# config.c is left out while its check and defaults become a table.
FNSIZE_SRC := $(filter-out firmware/config.c,$(FW_SRC)) $(wildcard firmware/*.h)

lint-fnsize:
	@echo "  FNSIZE  firmware: 80 body lines, nesting depth 4"
	$(Q)python3 tools/lint/fnsize.py $(FNSIZE_SRC)

# Every global symbol firmware/ defines, looked for in vehiclectl.
lint-client: $(BUILD)/vehiclectl $(FW_LIB)
	@echo "  NM      vehiclectl links no firmware"
	$(Q)nm -g --defined-only $(FW_LIB) | awk 'NF == 3 { print $$3 }' | sort -u >$(BUILD)/fw-symbols
	$(Q)hit=$$(nm -g --defined-only $(BUILD)/vehiclectl | awk 'NF == 3 { print $$3 }' | \
		sort -u | comm -12 - $(BUILD)/fw-symbols); \
	if [ -n "$$hit" ]; then echo "vehiclectl links firmware:" $$hit; exit 1; fi

lint-format:
	@echo "  FORMAT  .clang-format"
	$(Q)git ls-files '*.c' '*.h' | xargs clang-format --dry-run -Werror

lint-cppcheck:
	@echo "  CPPCHECK firmware proto hal host_sim tools"
	$(Q)cppcheck --quiet --std=c11 --enable=warning,style,performance,portability \
		--inline-suppr --suppressions-list=tools/lint/cppcheck.supp --error-exitcode=1 \
		-D_GNU_SOURCE -I. -I/usr/include/libevdev-1.0 $(LINT_SRC)

lint-tidy:
	@echo "  TIDY    $(words $(LINT_SRC)) files"
	$(Q)fail=0; for f in $(LINT_SRC); do \
		clang-tidy --quiet $$f -- $(LINT_DEFS) 2>/dev/null || fail=1; \
	done; exit $$fail

lint-warnings:
	@echo "  CLANG   -Wconversion -Wshadow firmware proto"
	$(Q)for f in $(FW_SRC); do \
		$(CLANG) $(LINT_DEFS) -fsyntax-only -ffreestanding $(WARN) $(STRICT) $$f || exit 1; done
	$(Q)for f in $(PROTO_SRC); do \
		$(CLANG) $(LINT_DEFS) -fsyntax-only $(WARN) $(STRICT) $$f || exit 1; done
