foreach(np 1 2 3 4)
  if(np EQUAL 1)
    mpm_add_test(test_p2g_np1 SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mpi/test_p2g.c
                 LABELS "unit;mpi" RANKS 1)
  else()
    mpm_add_test(test_p2g_np${np} EXE test_p2g_np1 LABELS "unit;mpi" RANKS ${np})
  endif()
endforeach()
