// a header with a broken define
#define OUTPUT_LAMP 5 *
