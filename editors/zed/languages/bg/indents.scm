(body "}" @end) @indent
(law_block "}" @end) @indent
