# lab.html = the page's template with its script (lab.js) and the
# WebAssembly module's script (Emscripten's output, the wasm inside as
# base64) written into it: one file that opens from a double click, with
# nothing fetched. Called by web/CMakeLists.txt:
#   cmake -DTEMPLATE=lab.html -DPAGE_SCRIPT=lab.js -DMODULE_SCRIPT=springlab_wasm.js -DOUT=... -P
file(READ "${TEMPLATE}" page)
foreach(part IN ITEMS MODULE_SCRIPT PAGE_SCRIPT)
  file(READ "${${part}}" text)
  # Inside <script>, only "</script" would end it early: written "<\/script".
  string(REPLACE "</script" "<\\/script" text "${text}")
  string(FIND "${page}" "/*@${part}@*/" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${TEMPLATE} has no /*@${part}@*/ placeholder")
  endif()
  string(REPLACE "/*@${part}@*/" "${text}" page "${page}")
endforeach()
file(WRITE "${OUT}.tmp" "${page}")
file(RENAME "${OUT}.tmp" "${OUT}")
