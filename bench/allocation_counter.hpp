#pragma once
// Heap allocations through the global operator new since the program started (replaced in
// allocation_counter.cpp), to measure what a stage allocates. C++ allocations only: Fortran's
// and C's malloc are not seen.
long heap_allocations();
