# SPDX-License-Identifier: MIT
# mk/cross.mk: boards (included at the end of the top Makefile).
#   make BOARD=<b> firmware   native boards: build/firmware/*.o as before;
#                             cross boards (board.mk sets BOARD_CROSS := 1):
#                             build/<b>/firmware.elf, size-checked, heap-free,
#                             and the board's budget printed
#   make boards               the firmware of every boards/*/board.mk, then the
#                             budget table
#   make boards-test          boards with a QEMU machine run their built-in fit
#   make boards-budget        the budget table (boards/README.md)

BOARDS_ALL := $(sort $(patsubst boards/%/board.mk,%,$(wildcard boards/*/board.mk)))
HOSTCC ?= cc
QEMU_TIMEOUT ?= 120
BUDGET_TOOL := $(BUILD)/tools/bd_budget

.PHONY: boards boards-test boards-budget board-budget board-qemu-test

boards:
	@set -e; for b in $(BOARDS_ALL); do \
	  echo "== board $$b"; \
	  $(MAKE) --no-print-directory BOARD=$$b BUILD=build/$$b firmware; \
	done
	@$(MAKE) --no-print-directory boards-budget

# Asked together (make -j boards boards-test), the run waits for the builds
# instead of racing them on the same files.
boards-test: $(filter boards,$(MAKECMDGOALS))
	@set -e; for b in $(BOARDS_ALL); do \
	  $(MAKE) --no-print-directory BOARD=$$b BUILD=build/$$b board-qemu-test; \
	done

boards-budget:
	@echo "| board | arena bytes | NF_MAX_CP | max degree | largest bicubic net, gs | chol | pcg | arena alone, gs / pcg |"
	@echo "|---|---|---|---|---|---|---|---|"
	@set -e; for b in $(BOARDS_ALL); do \
	  $(MAKE) -s --no-print-directory BOARD=$$b BUILD=build/$$b board-budget BUDGET_ARGS=--markdown; \
	done

# The byte formula evaluated on the host against this board's configuration
# (64-bit arithmetic whatever the target's long).
$(BUDGET_TOOL): boards/common/bd_budget.c $(FW_SRC) $(wildcard firmware/*.h) \
		boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(HOSTCC) -std=c11 $(WARN) -O2 -Iboards/$(BOARD) -Ifirmware -o $@ $< $(FW_SRC) -lm

board-budget: $(BUDGET_TOOL)
	@$(BUDGET_TOOL) $(BUDGET_ARGS)

ifeq ($(BOARD_CROSS),1)
FW_ELF := $(BUILD)/firmware.elf
FW_LDS := $(BUILD)/link.ld
BOARD_OBJ := $(patsubst boards/%.c,$(BUILD)/boards/%.o,$(BOARD_SRC))

firmware: $(FW_ELF)

# Board code with the firmware's flags and warnings.
$(BUILD)/boards/%.o: boards/%.c $(wildcard boards/common/*.h firmware/*.h) \
		boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) $(CFLAGS_ALL) -Iboards/common -c $< -o $@

# One set of sizes: the linker script is preprocessed with board_config.h.
$(FW_LDS): boards/$(BOARD)/link.ld.in boards/common/cortexm.ld boards/$(BOARD)/board_config.h
	@mkdir -p $(@D)
	$(CC) -E -P -undef -x c -Iboards/$(BOARD) -Iboards/common $< -o $@

# Linked to a temporary name: an image that fails a check is never left.
$(FW_ELF): $(BOARD_OBJ) $(FW_OBJ) $(FW_LDS) $(BUDGET_TOOL) mk/fwsize.sh
	$(CC) $(BOARD_ARCH) $(BOARD_LDFLAGS) -T $(FW_LDS) -Wl,-Map=$(BUILD)/firmware.map \
	  -o $@.tmp $(BOARD_OBJ) $(FW_OBJ) -lm
	@sh mk/fwsize.sh $(CROSS_COMPILE) $@.tmp $(BUILD)/firmware.map || { rm -f $@.tmp; exit 1; }
	@heap=$$($(CROSS_COMPILE)nm $@.tmp | grep -E ' (malloc|calloc|realloc|free|_malloc_r|_free_r|_sbrk|_sbrk_r)$$' || true); \
	if [ -n "$$heap" ]; then echo "$@: the image links the heap:"; echo "$$heap"; rm -f $@.tmp; exit 1; fi
	@mv $@.tmp $@
	@echo "$@: no heap, every region within its length"
	@$(BUDGET_TOOL)

endif

ifneq ($(BOARD_QEMU_MACHINE),)
board-qemu-test: $(FW_ELF) $(BUDGET_TOOL)
	@sh mk/qemu-test.sh run $(BOARD_QEMU_MACHINE) $(FW_ELF) $(QEMU_TIMEOUT) $(BUDGET_TOOL)
else
# Boards without an emulator have nothing to run.
board-qemu-test:
	@:
endif
