# VehicleService over CORBA (omniORB 4.2, docs/corba.md; included from the
# top Makefile).
#
#   build/vehicle-corba          the gateway: the appendix IDL served over
#                                CORBA, each call forwarded through proto/client/client.h
#   build/tests/vs-corba-client  the test client, stubs from the same IDL
#   make check                   tests/corba/run.sh: omniNames on loopback, the
#                                gateway against vehicle-sim --pty --fast, the
#                                client through the naming service
#
# C++ with its own flags (not the firmware's C set), warnings still errors;
# the omniidl output is built with the same flags and left out of make lint.

OMNIIDL ?= omniidl
CXX ?= g++
CORBA_IDL := tools/corba/VehicleService.idl
CORBA_GEN := $(BUILD)/corba/gen
CORBA_STUB_HH := $(CORBA_GEN)/VehicleService.hh
CORBA_STUB_CC := $(CORBA_GEN)/VehicleServiceSK.cc
CORBA_OBJ := $(BUILD)/corba/obj
# The sanitizer and coverage switches of the C build carry over.
CORBA_CXXFLAGS := -std=c++17 $(OPT) -g -Wall -Wextra -Werror -Wshadow -MMD -MP -I. \
	-I$(CORBA_GEN) $(filter -fsanitize% -fno-sanitize% -fno-omit-frame-pointer --coverage \
	-O0,$(CFLAGS_BASE))
# GCC 12 under -fsanitize=address sees the servant's virtual base through the
# instrumented allocation and reports a false -Warray-bounds in omniidl's
# skeleton constructor; the plain build keeps the warning.
ifeq ($(SANITIZE),1)
CORBA_CXXFLAGS += -Wno-array-bounds
endif
CORBA_LDLIBS := -lomniORB4 -lomnithread -lpthread
CORBA_CLIBS := $(PROTO_LIB) $(HOST_LIB) $(FW_LIB)
CORBA_FMT_SRC := $(wildcard tools/corba/*.cc tests/corba/*.cc)

.PHONY: corba lint-corba
corba: $(BUILD)/vehicle-corba $(BUILD)/tests/vs-corba-client
all: corba

# The stubs and skeletons, generated from the committed IDL (which
# tests/corba/run.sh checks against the specification's appendix).
$(CORBA_STUB_HH) $(CORBA_STUB_CC) &: $(CORBA_IDL)
	@mkdir -p $(CORBA_GEN)
	@$(if $(Q),echo "  OMNIIDL $<")
	$(Q)$(OMNIIDL) -bcxx -Wbh=.hh -Wbs=SK.cc -C$(CORBA_GEN) $<

$(CORBA_OBJ)/%.o: $(CORBA_GEN)/%.cc $(CORBA_STUB_HH)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CXX     $<")
	$(Q)$(CXX) $(CORBA_CXXFLAGS) -c $< -o $@

$(CORBA_OBJ)/%.o: tools/corba/%.cc $(CORBA_STUB_HH)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CXX     $<")
	$(Q)$(CXX) $(CORBA_CXXFLAGS) -c $< -o $@

$(CORBA_OBJ)/tests/%.o: tests/corba/%.cc $(CORBA_STUB_HH)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CXX     $<")
	$(Q)$(CXX) $(CORBA_CXXFLAGS) -c $< -o $@

$(BUILD)/vehicle-corba: $(CORBA_OBJ)/vehicle_corba_main.o $(CORBA_OBJ)/VehicleServiceSK.o \
		$(CORBA_CLIBS)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CXX) $(LDFLAGS) -o $@ $^ $(LDLIBS_HOST) $(CORBA_LDLIBS)

$(BUILD)/tests/vs-corba-client: $(CORBA_OBJ)/tests/vs_corba_client.o \
		$(CORBA_OBJ)/VehicleServiceSK.o
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  LD      $@")
	$(Q)$(CXX) $(LDFLAGS) -o $@ $^ $(CORBA_LDLIBS)

CHECK_SUITES += tests/corba/run.sh

# The hand-written C++ follows .clang-format too (generated code is not linted).
lint: lint-corba
lint-corba:
	@echo "  FORMAT  $(words $(CORBA_FMT_SRC)) C++ files"
	$(Q)clang-format --dry-run -Werror $(CORBA_FMT_SRC)

-include $(shell find $(CORBA_OBJ) -name '*.d' 2>/dev/null)
