#pragma once
// Heap allocations of the whole process since it started (malloc family and operator new,
// replaced in allocation_counter.cpp), to measure what a stage allocates. Link the .cpp into a
// program of its own: it replaces malloc for the whole process (the benchmark and
// test_realtime do).
/// -1 in AddressSanitizer builds (which own malloc).
long heap_allocations();
