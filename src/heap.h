/*
 * heap.h - indexed 4-ary max-heap with update (internal).
 *
 * Items are dense indices 0..capacity-1 (edge slots of the simplifier), each
 * in the heap at most once with a double key. Order: larger key first, equal
 * keys by smaller item index, so the pop sequence depends only on the set of
 * (key, item) pairs and never on the order of insertion or on the array
 * layout: results repeat (ARCHITECTURE.md, "Deterministic").
 */
#ifndef FEMLOD_HEAP_H
#define FEMLOD_HEAP_H

#include "core.h"

typedef struct fl_heap_entry {
    double key;
    uint32_t item;
} fl_heap_entry;

typedef struct fl_heap {
    fl_heap_entry *e; /* n entries in heap order (inside base, aligned) */
    fl_heap_entry *base;
    uint32_t *pos;    /* capacity: heap index of each item, UINT32_MAX when absent */
    size_t n, capacity;
} fl_heap;

/* 0 on ENOMEM. */
FL_INTERNAL int fl_heap_init(fl_heap *h, size_t capacity);
FL_INTERNAL void fl_heap_free(fl_heap *h);
/* Inserts item or changes its key. */
FL_INTERNAL void fl_heap_set(fl_heap *h, uint32_t item, double key);
/* Removes item when present. */
FL_INTERNAL void fl_heap_remove(fl_heap *h, uint32_t item);
/* Removes and returns the first item; UINT32_MAX when empty. */
FL_INTERNAL uint32_t fl_heap_pop(fl_heap *h, double *key);

static inline int fl_heap_contains(const fl_heap *h, uint32_t item) { return h->pos[item] != UINT32_MAX; }
static inline size_t fl_heap_size(const fl_heap *h) { return h->n; }
/* The first item (the heap must not be empty). */
static inline uint32_t fl_heap_top(const fl_heap *h) { return h->e[0].item; }
/* The first key; -inf when empty. */
static inline double fl_heap_top_key(const fl_heap *h) { return h->n ? h->e[0].key : -__builtin_inf(); }

#endif
