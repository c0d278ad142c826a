# Environment for tests that start MPI ranks (included after the discovered
# tests, like ctest_costs.cmake). Under scripts/sanitize, OpenMPI's plugins
# leak one-time allocations and are unloaded before LeakSanitizer reports, so
# the fast unwinder leaves their stacks as "<unknown module>"; the slow
# (DWARF) unwinder reaches the libmpi / libopen-pal frames that
# tests/sanitizers/lsan.supp suppresses. Slow, so only here. Without ASan the
# variable is read by nobody.
foreach(name
    "Sweep: under mpirun the points and tables equal a local run's"
    "CLI: train --jobs 2 and mpirun simulate the episodes one job does, byte for byte, and extend a saved set exactly")
  set_tests_properties("${name}" PROPERTIES
    ENVIRONMENT_MODIFICATION "ASAN_OPTIONS=string_append::fast_unwind_on_malloc=0")
endforeach()
