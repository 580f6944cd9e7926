#pragma once
// Heap allocations of the whole process since it started (malloc family and operator new,
// replaced in allocation_counter.cpp), to measure what a stage allocates.
/// -1 in AddressSanitizer builds (which own malloc).
long heap_allocations();
