/**
 * Tree-sitter grammar for bgc's bond-graph language (`.bg` files), after the grammar in docs/language.md.
 *
 * It is made for editors (highlighting, outline, brackets), not for compiling: it accepts a little more than bgc
 * does (bgc's parser reports the rest with located diagnostics through `bgc lsp`). A unit `[N m/rad]` is one
 * token: where a unit may follow an expression (a parameter's default), `n [1]` is `n` with the unit `[1]`, as
 * bgc reads it.
 */

const PREC = {
  sum: 1,
  product: 2,
  unary: 3,
  power: 4,
};

const commaSep1 = (rule) => seq(rule, repeat(seq(',', rule)));
const commaSep = (rule) => optional(commaSep1(rule));

module.exports = grammar({
  name: 'bg',

  extras: ($) => [/\s/, $.comment],

  word: ($) => $.identifier,

  rules: {
    source_file: ($) => repeat($._item),

    _item: ($) => choice($.import, $.model, $.component, ';'),

    import: ($) => seq('import', field('path', $.string), ';'),

    model: ($) => seq('model', field('name', $.identifier), $.body),

    component: ($) => seq('component', field('name', $.identifier), $.body),

    body: ($) => seq('{', repeat($._statement), '}'),

    _statement: ($) =>
      choice(
        $.domain_declaration,
        $.param_declaration,
        $.input_declaration,
        $.output_declaration,
        $.var_declaration,
        $.coords_declaration,
        $.element,
        $.instance,
        $.bond,
        $.port_declaration,
        $.allow,
        ';',
      ),

    domain_declaration: ($) => seq('domain', field('domain', $.identifier), ';'),

    param_declaration: ($) =>
      seq(
        'param',
        field('name', $.identifier),
        '=',
        field('value', $._expression),
        field('unit', $.unit),
        optional(field('description', $.string)),
        ';',
      ),

    input_declaration: ($) =>
      seq(
        'input',
        field('name', $.identifier),
        field('unit', $.unit),
        optional(field('description', $.string)),
        ';',
      ),

    output_declaration: ($) =>
      seq(
        'output',
        field('name', $.identifier),
        field('unit', $.unit),
        '=',
        field('value', $._expression),
        optional(field('description', $.string)),
        ';',
      ),

    var_declaration: ($) =>
      seq('var', field('name', $.identifier), field('unit', $.unit), '=', field('value', $._expression), ';'),

    coords_declaration: ($) => seq('coords', '[', commaSep1($._expression), ']', ';'),

    element: ($) =>
      seq(
        field('kind', $.element_kind),
        field('name', $.identifier),
        optional(seq('(', field('ports', $.number), ')')),
        optional(seq(':', field('domain', $.identifier))),
        // The `;` a law block may have after it is an empty statement.
        choice(seq('=', field('value', $._expression), ';'), $.law_block, ';'),
      ),

    element_kind: (_) =>
      choice('Se', 'Sf', 'MSe', 'MSf', 'C', 'I', 'R', 'TF', 'GY', 'MTF', 'MGY', '0', '1', 'CF', 'RF', 'IF'),

    law_block: ($) => seq('{', repeat($.law), '}'),

    law: ($) =>
      seq(
        field('variable', $.identifier),
        optional(seq('[', commaSep1($.number), ']')),
        '=',
        field('value', $._expression),
        ';',
      ),

    instance: ($) =>
      seq(
        field('component', $.identifier),
        field('name', $.identifier),
        optional(seq('(', commaSep($.override), ')')),
        ';',
      ),

    override: ($) => seq(field('name', $.identifier), '=', field('value', $._expression)),

    bond: ($) =>
      seq(
        'bond',
        optional(seq(field('label', $.identifier), ':')),
        $.group,
        repeat1(seq('->', $.group)),
        optional($.stroke),
        ';',
      ),

    group: ($) => commaSep1($.node),

    stroke: ($) => seq('stroke', optional('!'), $.node),

    node: ($) => seq($.identifier, repeat(seq('.', $.identifier)), optional(seq('[', $.number, ']'))),

    port_declaration: ($) => seq('port', field('name', $.identifier), '=', $.node, ';'),

    allow: ($) =>
      seq('allow', field('code', alias($.identifier, $.code)), $.node, optional(field('reason', $.string)), ';'),

    _expression: ($) =>
      choice(
        $.number,
        $.name,
        $.index,
        $.call,
        $.parenthesized,
        $.unary,
        $.binary,
      ),

    name: ($) => seq($.identifier, repeat(seq('.', $.identifier))),

    index: ($) => seq($.identifier, '[', $.number, ']'),

    call: ($) => seq(field('function', $.identifier), '(', commaSep($._expression), ')'),

    parenthesized: ($) => seq('(', $._expression, ')'),

    unary: ($) => prec(PREC.unary, seq('-', $._expression)),

    binary: ($) =>
      choice(
        prec.left(PREC.sum, seq($._expression, choice('+', '-'), $._expression)),
        prec.left(PREC.product, seq($._expression, choice('*', '/'), $._expression)),
        prec.right(PREC.power, seq($._expression, '^', $._expression)),
      ),

    unit: (_) => token(seq('[', /[^\]\n]*/, ']')),

    identifier: (_) => /[A-Za-z_][A-Za-z0-9_]*/,

    number: (_) => token(choice(/[0-9]+(\.[0-9]*)?([eE][+-]?[0-9]+)?/, /\.[0-9]+([eE][+-]?[0-9]+)?/)),

    string: (_) => token(seq('"', repeat(choice(/[^"\\\n]/, /\\./)), '"')),

    comment: (_) => token(seq('//', /[^\n]*/)),
  },
});
