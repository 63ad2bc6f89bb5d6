/*
 * heap.c - indexed binary max-heap with update, the simplifier's priority
 * queue (paper section 4.2.3: the edge with the largest priority index is
 * collapsed first). Shaped after PMP's decimation heap (pmp/algorithms/
 * heap.h): a position array per item makes update and removal O(log n), so
 * the queue holds each edge once and never fills with stale copies.
 *
 * Four children per node (D = 4): half the depth of a binary heap, and the
 * four children of a node are adjacent in memory, so a sift-down through a
 * queue of millions of edges touches about half the cache lines (most key
 * changes in the simplifier are decreases, which sift down). The order is
 * the same total order on (key, item) as for any heap shape, so the pop
 * sequence does not depend on D.
 */
#include "heap.h"

#include <stdint.h>
#include <stdlib.h>

/* a goes before b */
static inline int before(const fl_heap_entry *a, const fl_heap_entry *b) {
    return a->key > b->key || (a->key == b->key && a->item < b->item);
}

int fl_heap_init(fl_heap *h, size_t capacity) {
    h->n = 0;
    h->capacity = capacity;
    /* 4 spare entries: e[1] (and so every group of four children) starts a
     * 64-byte cache line */
    /* the positions are all written below, so mapped at once (fl_populate);
     * the entries fill only as far as the queue grows (after fast passes, a
     * small part of the edges), so their pages fault when first used */
    h->base = fl_alloc(capacity + 4, sizeof *h->e);
    h->pos = fl_populate(fl_alloc(capacity, sizeof *h->pos), capacity * sizeof *h->pos);
    if (h->base) {
        size_t skip = (64 - ((uintptr_t)(h->base + 1) & 63)) % 64 / sizeof *h->e;
        h->e = h->base + skip;
    }
    if (!h->base || !h->pos) {
        fl_heap_free(h);
        return 0;
    }
    for (size_t i = 0; i < capacity; i++) h->pos[i] = UINT32_MAX;
    return 1;
}

void fl_heap_free(fl_heap *h) {
    free(h->base);
    free(h->pos);
    h->base = h->e = NULL;
    h->pos = NULL;
    h->n = h->capacity = 0;
}

#define D 4

static void sift_up(fl_heap *h, size_t i) {
    fl_heap_entry x = h->e[i];
    while (i > 0) {
        size_t p = (i - 1) / D;
        if (!before(&x, &h->e[p])) break;
        h->e[i] = h->e[p];
        h->pos[h->e[i].item] = (uint32_t)i;
        i = p;
    }
    h->e[i] = x;
    h->pos[x.item] = (uint32_t)i;
}

static void sift_down(fl_heap *h, size_t i) {
    fl_heap_entry x = h->e[i];
    size_t n = h->n;
    for (;;) {
        size_t c = D * i + 1;
        if (c >= n) break;
        size_t end = c + D < n ? c + D : n;
        for (size_t d = c + 1; d < end; d++)
            if (before(&h->e[d], &h->e[c])) c = d;
        if (!before(&h->e[c], &x)) break;
        h->e[i] = h->e[c];
        h->pos[h->e[i].item] = (uint32_t)i;
        i = c;
    }
    h->e[i] = x;
    h->pos[x.item] = (uint32_t)i;
}

void fl_heap_set(fl_heap *h, uint32_t item, double key) {
    uint32_t p = h->pos[item];
    if (p == UINT32_MAX) {
        size_t i = h->n++;
        h->e[i].key = key;
        h->e[i].item = item;
        sift_up(h, i);
        return;
    }
    double old = h->e[p].key;
    h->e[p].key = key;
    if (key > old) sift_up(h, p);
    else if (key < old) sift_down(h, p);
}

void fl_heap_remove(fl_heap *h, uint32_t item) {
    uint32_t p = h->pos[item];
    if (p == UINT32_MAX) return;
    h->pos[item] = UINT32_MAX;
    size_t last = --h->n;
    if (p == last) return;
    h->e[p] = h->e[last];
    h->pos[h->e[p].item] = p;
    if (p > 0 && before(&h->e[p], &h->e[(p - 1) / D])) sift_up(h, p);
    else sift_down(h, p);
}

uint32_t fl_heap_pop(fl_heap *h, double *key) {
    if (h->n == 0) return UINT32_MAX;
    uint32_t item = h->e[0].item;
    if (key) *key = h->e[0].key;
    fl_heap_remove(h, item);
    return item;
}
