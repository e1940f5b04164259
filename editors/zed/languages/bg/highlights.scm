; Highlighting of .bg files (captures from Zed's default theme names).

(comment) @comment
(string) @string
(number) @number
(unit) @type

[
  "import"
  "model"
  "component"
  "domain"
  "param"
  "input"
  "output"
  "var"
  "coords"
  "bond"
  "port"
  "allow"
  "stroke"
] @keyword

(element_kind) @type.builtin

(model name: (identifier) @type)
(component name: (identifier) @type)
(instance component: (identifier) @type)
(instance name: (identifier) @variable)

(param_declaration name: (identifier) @constant)
(input_declaration name: (identifier) @variable.parameter)
(output_declaration name: (identifier) @property)
(var_declaration name: (identifier) @property)
(port_declaration name: (identifier) @property)
(element name: (identifier) @function)
(domain_declaration domain: (identifier) @constant.builtin)
(element domain: (identifier) @constant.builtin)
(law variable: (identifier) @variable.special)
(override name: (identifier) @property)
(bond label: (identifier) @label)
(allow code: (code) @constant.builtin)

(call function: (identifier) @function.builtin)

((name (identifier) @constant.builtin)
  (#any-of? @constant.builtin "pi" "t"))

["->" "=" "+" "-" "*" "/" "^" "!"] @operator
["(" ")" "[" "]" "{" "}"] @punctuation.bracket
["," ";" ":" "."] @punctuation.delimiter
