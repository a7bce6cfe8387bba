"""What a symbol or a completion item is (``plcbuilder.lang.symbols`` answers
with these); a module of its own so that the IDE names the kinds without
loading the preprocessor."""

KEYWORD = "keyword"
FUNCTION = "function"
PREDEFINED_VARIABLE = "predefined"
DEFINE = "define"
PROCEDURE = "procedure"
VARIABLE = "variable"
CONSTANT = "constant"
