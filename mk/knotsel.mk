# SPDX-License-Identifier: MIT
# mk/knotsel.mk: the knot chooser's loop (firmware/nf_knotsel, nf_loopctl)
# as a benchmark driver, and the loop benchmark beside FITPACK's surfit
# (bench/loop_bench.py; prints a table, asserts nothing).
#   make knotsel-loop   build/knotsel_loop
#   make bench-loop     the table (about a minute on 2 cores; LOOP_BENCH_ARGS)
KNOTSEL_LOOP := $(BUILD)/knotsel_loop
LOOP_BENCH_ARGS ?=

.PHONY: knotsel-loop bench-loop
knotsel-loop: $(KNOTSEL_LOOP)

$(KNOTSEL_LOOP): bench/knotsel_loop.c tests/unit/ref_kloop.c $(FW_OBJ)
	$(CC) $(CFLAGS_ALL) -o $@ bench/knotsel_loop.c tests/unit/ref_kloop.c $(FW_OBJ) -lm

bench-loop: $(BUILD)/cellfit $(KNOTSEL_LOOP)
	@sh scripts/deps.sh bench
	@/usr/bin/python3 bench/loop_bench.py --cellfit $(BUILD)/cellfit --knotsel $(KNOTSEL_LOOP) $(LOOP_BENCH_ARGS)
