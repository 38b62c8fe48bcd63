/* SPDX-License-Identifier: MIT */
/* scan_cost.py: what the hand-written benchmark programs share. */
#ifndef HAND_H
#define HAND_H
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* the task context of the hand-written programs: time and the first fault */
struct hand_ctx {
	int64_t now_ns;
	int fault;		/* 0: none */
	int fault_line;
};

#endif
