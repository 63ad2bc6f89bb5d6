# cmake -DA=prog -DB=prog -DDATA=folder [-DLABEL_A=text -DLABEL_B=text]
# -P scan_compare.cmake: runs both digest programs on DATA and fails unless
# each succeeds and their outputs are identical (tests/c/scan_digest.c).
if(NOT DEFINED LABEL_A)
  set(LABEL_A "one side per face")
endif()
if(NOT DEFINED LABEL_B)
  set(LABEL_B "marked scan")
endif()
foreach(p A B)
  execute_process(COMMAND ${${p}} ${DATA} OUTPUT_VARIABLE out_${p} RESULT_VARIABLE rc_${p})
  if(NOT rc_${p} EQUAL 0)
    message(FATAL_ERROR "${${p}} failed (${rc_${p}}):\n${out_${p}}")
  endif()
endforeach()
message("${LABEL_A}:\n${out_A}${LABEL_B}:\n${out_B}")
if(NOT out_A STREQUAL out_B)
  message(FATAL_ERROR "${LABEL_A} and ${LABEL_B} gave different results")
endif()
