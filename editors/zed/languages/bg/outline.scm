(model "model" @context name: (identifier) @name) @item
(component "component" @context name: (identifier) @name) @item
(param_declaration "param" @context name: (identifier) @name) @item
(input_declaration "input" @context name: (identifier) @name) @item
(output_declaration "output" @context name: (identifier) @name) @item
(var_declaration "var" @context name: (identifier) @name) @item
(element kind: (element_kind) @context name: (identifier) @name) @item
(instance component: (identifier) @context name: (identifier) @name) @item
