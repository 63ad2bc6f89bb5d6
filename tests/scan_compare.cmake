# cmake -DA=prog -DB=prog -DDATA=folder -P scan_compare.cmake: runs both
# digest programs on DATA and fails unless each succeeds and their outputs
# are identical (tests/c/scan_digest.c).
foreach(p A B)
  execute_process(COMMAND ${${p}} ${DATA} OUTPUT_VARIABLE out_${p} RESULT_VARIABLE rc_${p})
  if(NOT rc_${p} EQUAL 0)
    message(FATAL_ERROR "${${p}} failed (${rc_${p}}):\n${out_${p}}")
  endif()
endforeach()
message("one side per face:\n${out_A}marked scan:\n${out_B}")
if(NOT out_A STREQUAL out_B)
  message(FATAL_ERROR "the two scans gave different results")
endif()
