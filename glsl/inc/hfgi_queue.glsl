// hfgi — the indirect scan's walk state (glsl/indirect/scan.comp.glsl; docs/performance.md §18, §33):
// the queue of members found and not yet cast, the cast merge's held member, the replay's
// record of the probe-less walk's members, and the one comparison of every walk. Needs
// HFGI_QUEUE and HFGI_MERGE (the scan's constants) defined before it.
#ifndef HFGI_QUEUE_GLSL
#define HFGI_QUEUE_GLSL
// Members a lane has found and not yet cast, in order (docs/performance.md §18): the slope, the
// step t and the ladder sample index of each. A lane walks on past its members while the subgroup's
// other lanes look for theirs; the subgroup casts when one lane's queue is full, one member per
// lane, so lanes neither wait for one another's members nor cast alone. With the cast merge
// (HFGI_MERGE) also the slope of the last member queued (`kept`) and the step and sample of the
// last member found (`last_t`, `last_i`): that member is held while the walk's horizon, its
// slope, is above `kept`.
struct hfgi_Queue {
    float slope[HFGI_QUEUE];
    float t[HFGI_QUEUE];
    int i[HFGI_QUEUE];
    int count;
    float kept;
    float last_t;
    int last_i;
};

hfgi_Queue queue_empty(float running_slope) {
    hfgi_Queue m;
    [[unroll]] for (int k = 0; k < HFGI_QUEUE; ++k) {
        m.slope[k] = 0.0;
        m.t[k] = 1.0;
        m.i[k] = 0;
    }
    m.count = 0;
    m.kept = running_slope;
    m.last_t = 1.0;
    m.last_i = 0;
    return m;
}

// Whether a member of slope s is kept (cast) rather than held, the last member kept having slope
// c: its elevation is at least δ above c's, tan(ω_s − ω_c) = (s − c)/(1 + s·c) ≥ tan δ (with
// 1 + s·c ≤ 0 the difference exceeds π/2 and the left side already holds). Always without
// the merge.
bool merge_keeps(float s, float c) {
    return HFGI_MERGE == 0.0 || s - c >= HFGI_MERGE * (1.0 + s * c);
}

// The members of the walk without probes, one bit per ladder sample (HFGI_REPLAY = 1): bits
// 0–31 and 32–63 of sample k = i − first. Set as the walk finds them, stored at the ray's end.
uvec2 hfgi_plain;

void plain_record(int i, int first) {
    int k = i - first;
    uint one = 1u << uint(k & 31);
    hfgi_plain |= k < 32 ? uvec2(one, 0u) : uvec2(0u, one);
}

// Whether a sample at step t with height difference dh rises above the horizon `slope` (eq. 15
// multiplied out); if so the horizon becomes its slope. The one comparison of every walk: the
// probed walk's, and the probe-less walk's whose members the replay records (so both find the
// same members, docs/indirect.md §2).
bool rises(inout float slope, float dh, float t, float texel) {
    if (dh > slope * (t * texel)) {
        slope = dh / (t * texel);
        return true;
    }
    return false;
}

// Appends a member to the queue (which has room).
void queue_push(inout hfgi_Queue m, float slope, float t, int i) {
    [[unroll]] for (int k = 0; k < HFGI_QUEUE; ++k) {
        if (k == m.count) {
            m.slope[k] = slope;
            m.t[k] = t;
            m.i[k] = i;
        }
    }
    ++m.count;
}

// A sample at step t with height difference dh: if it rises above the walk's horizon it is a
// member, queued, or with the cast merge held when less than δ above the last one kept.
void queue_sample(inout hfgi_Queue m, inout float walk_slope, float dh, float t, int i, float texel) {
    if (rises(walk_slope, dh, t, texel)) {
        if (HFGI_MERGE != 0.0) {
            m.last_t = t;
            m.last_i = i;
        }
        if (merge_keeps(walk_slope, m.kept)) {
            queue_push(m, walk_slope, t, i);
            m.kept = walk_slope;
        }
    }
}

// Whether the walk with horizon `walk_slope` holds a member (the cast merge).
bool queue_holds(hfgi_Queue m, float walk_slope) {
    return HFGI_MERGE != 0.0 && walk_slope != m.kept;
}

// At the ray's end: the member held, if any, is queued (when the queue has room).
void queue_end(inout hfgi_Queue m, float walk_slope) {
    if (queue_holds(m, walk_slope) && m.count < HFGI_QUEUE) {
        queue_push(m, walk_slope, m.last_t, m.last_i);
        m.kept = walk_slope;
    }
}
#endif
