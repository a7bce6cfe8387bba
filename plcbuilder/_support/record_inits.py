"""The ``__init__`` templates of the shapes of the package's record classes
(:mod:`plcbuilder._support.records`), loaded from this module's bytecode
cache instead of compiled at every start. Written by
``scripts/record_inits.py``; tests/_support/test_records.py
checks it is current. The names each template uses are the globals the
records module gives the class's ``__init__``."""
# (generated: do not edit)


def _init0(self, a0):
    if a0 is MISSING: a0 = _f0()
    self.a0 = a0


def _init1(self, a0, a1, a2):
    if a0 is MISSING: a0 = _f0()
    self.a0 = a0
    if a1 is MISSING: a1 = _f1()
    self.a1 = a1
    if a2 is MISSING: a2 = _f2()
    self.a2 = a2


def _init2(self, a0, a1, a2, a3, a4, a5):
    if a0 is MISSING: a0 = _f0()
    self.a0 = a0
    if a1 is MISSING: a1 = _f1()
    self.a1 = a1
    if a2 is MISSING: a2 = _f2()
    self.a2 = a2
    if a3 is MISSING: a3 = _f3()
    self.a3 = a3
    if a4 is MISSING: a4 = _f4()
    self.a4 = a4
    if a5 is MISSING: a5 = _f5()
    self.a5 = a5


def _init3(self, a0, a1):
    if a0 is MISSING: a0 = _f0()
    self.a0 = a0
    self.a1 = a1


def _init4(self, a0):
    self.a0 = a0


def _init5(self, a0, a1):
    self.a0 = a0
    self.a1 = a1


def _init6(self, a0, a1):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)


def _init7(self, a0, a1, a2, a3, a4, a5):
    self.a0 = a0
    self.a1 = a1
    if a2 is MISSING: a2 = _f2()
    self.a2 = a2
    if a3 is MISSING: a3 = _f3()
    self.a3 = a3
    if a4 is MISSING: a4 = _f4()
    self.a4 = a4
    if a5 is MISSING: a5 = _f5()
    self.a5 = a5


def _init8(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    if a2 is MISSING: a2 = _f2()
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)
    __record_set(self, 'a9', a9)
    __record_set(self, 'a10', a10)
    __record_set(self, 'a11', a11)


def _init9(self, a0, a1, a2):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2


def _init10(self, a0, a1, a2):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.__post_init__()


def _init11(self, a0, a1, a2):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)


def _init12(self, a0, a1, a2, a3):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    if a3 is MISSING: a3 = _f3()
    self.a3 = a3


def _init13(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    if a3 is MISSING: a3 = _f3()
    self.a3 = a3
    if a4 is MISSING: a4 = _f4()
    self.a4 = a4
    if a5 is MISSING: a5 = _f5()
    self.a5 = a5
    if a6 is MISSING: a6 = _f6()
    self.a6 = a6
    if a7 is MISSING: a7 = _f7()
    self.a7 = a7
    self.a8 = a8
    self.a9 = a9
    if a10 is MISSING: a10 = _f10()
    self.a10 = a10


def _init14(self, a0, a1, a2, a3, a4):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    if a3 is MISSING: a3 = _f3()
    self.a3 = a3
    self.a4 = a4


def _init15(self, a0, a1, a2, a3):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3


def _init16(self, a0, a1, a2, a3):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)


def _init17(self, a0, a1, a2, a3, a4):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    if a4 is MISSING: a4 = _f4()
    self.a4 = a4


def _init18(self, a0, a1, a2, a3, a4, a5, a6, a7):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    if a4 is MISSING: a4 = _f4()
    self.a4 = a4
    if a5 is MISSING: a5 = _f5()
    self.a5 = a5
    if a6 is MISSING: a6 = _f6()
    self.a6 = a6
    if a7 is MISSING: a7 = _f7()
    self.a7 = a7


def _init19(self, a0, a1, a2, a3, a4):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4


def _init20(self, a0, a1, a2, a3, a4):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)


def _init21(self, a0, a1, a2, a3, a4, a5, a6, a7):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    if a5 is MISSING: a5 = _f5()
    self.a5 = a5
    if a6 is MISSING: a6 = _f6()
    self.a6 = a6
    self.a7 = a7


def _init22(self, a0, a1, a2, a3, a4, a5):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5


def _init23(self, a0, a1, a2, a3, a4, a5):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)


def _init24(self, a0, a1, a2, a3, a4, a5, a6):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6


def _init25(self, a0, a1, a2, a3, a4, a5, a6):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)


def _init26(self, a0, a1, a2, a3, a4, a5, a6, a7, a8):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    if a7 is MISSING: a7 = _f7()
    self.a7 = a7
    self.a8 = a8


def _init27(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    if a7 is MISSING: a7 = _f7()
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)
    __record_set(self, 'a9', a9)
    __record_set(self, 'a10', a10)
    __record_set(self, 'a11', a11)
    __record_set(self, 'a12', a12)
    __record_set(self, 'a13', a13)


def _init28(self, a0, a1, a2, a3, a4, a5, a6, a7):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7


def _init29(self, a0, a1, a2, a3, a4, a5, a6, a7):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)


def _init30(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7
    if a8 is MISSING: a8 = _f8()
    self.a8 = a8
    if a9 is MISSING: a9 = _f9()
    self.a9 = a9
    self.a10 = a10
    self.a11 = a11


def _init31(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7
    if a8 is MISSING: a8 = _f8()
    self.a8 = a8
    self.a9 = a9
    if a10 is MISSING: a10 = _f10()
    self.a10 = a10


def _init32(self, a0, a1, a2, a3, a4, a5, a6, a7, a8):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)


def _init33(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7
    self.a8 = a8
    self.a9 = a9
    self.a10 = a10


def _init34(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)
    __record_set(self, 'a9', a9)
    __record_set(self, 'a10', a10)
    if a11 is MISSING: a11 = _f11()
    __record_set(self, 'a11', a11)
    __record_set(self, 'a12', a12)
    __record_set(self, 'a13', a13)
    if a14 is MISSING: a14 = _f14()
    __record_set(self, 'a14', a14)
    if a15 is MISSING: a15 = _f15()
    __record_set(self, 'a15', a15)
    if a16 is MISSING: a16 = _f16()
    __record_set(self, 'a16', a16)


def _init35(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7
    self.a8 = a8
    self.a9 = a9
    self.a10 = a10
    self.a11 = a11


def _init36(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)
    __record_set(self, 'a9', a9)
    __record_set(self, 'a10', a10)
    __record_set(self, 'a11', a11)
    __record_set(self, 'a12', a12)


def _init37(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14):
    __record_set(self, 'a0', a0)
    __record_set(self, 'a1', a1)
    __record_set(self, 'a2', a2)
    __record_set(self, 'a3', a3)
    __record_set(self, 'a4', a4)
    __record_set(self, 'a5', a5)
    __record_set(self, 'a6', a6)
    __record_set(self, 'a7', a7)
    __record_set(self, 'a8', a8)
    __record_set(self, 'a9', a9)
    __record_set(self, 'a10', a10)
    __record_set(self, 'a11', a11)
    __record_set(self, 'a12', a12)
    __record_set(self, 'a13', a13)
    __record_set(self, 'a14', a14)


def _init38(self, a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16, a17, a18, a19, a20, a21, a22, a23, a24, a25):
    self.a0 = a0
    self.a1 = a1
    self.a2 = a2
    self.a3 = a3
    self.a4 = a4
    self.a5 = a5
    self.a6 = a6
    self.a7 = a7
    self.a8 = a8
    self.a9 = a9
    self.a10 = a10
    self.a11 = a11
    self.a12 = a12
    self.a13 = a13
    self.a14 = a14
    self.a15 = a15
    self.a16 = a16
    self.a17 = a17
    self.a18 = a18
    self.a19 = a19
    self.a20 = a20
    self.a21 = a21
    self.a22 = a22
    self.a23 = a23
    self.a24 = a24
    self.a25 = a25


SHAPES = {
    (('f',), False, False): _init0,
    (('f', 'f', 'f'), False, False): _init1,
    (('f', 'f', 'f', 'f', 'f', 'f'), False, False): _init2,
    (('f', 'p'), False, False): _init3,
    (('p',), False, False): _init4,
    (('p', 'p'), False, False): _init5,
    (('p', 'p'), True, False): _init6,
    (('p', 'p', 'f', 'f', 'f', 'f'), False, False): _init7,
    (('p', 'p', 'f', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init8,
    (('p', 'p', 'p'), False, False): _init9,
    (('p', 'p', 'p'), False, True): _init10,
    (('p', 'p', 'p'), True, False): _init11,
    (('p', 'p', 'p', 'f'), False, False): _init12,
    (('p', 'p', 'p', 'f', 'f', 'f', 'f', 'f', 'p', 'p', 'f'), False, False): _init13,
    (('p', 'p', 'p', 'f', 'p'), False, False): _init14,
    (('p', 'p', 'p', 'p'), False, False): _init15,
    (('p', 'p', 'p', 'p'), True, False): _init16,
    (('p', 'p', 'p', 'p', 'f'), False, False): _init17,
    (('p', 'p', 'p', 'p', 'f', 'f', 'f', 'f'), False, False): _init18,
    (('p', 'p', 'p', 'p', 'p'), False, False): _init19,
    (('p', 'p', 'p', 'p', 'p'), True, False): _init20,
    (('p', 'p', 'p', 'p', 'p', 'f', 'f', 'p'), False, False): _init21,
    (('p', 'p', 'p', 'p', 'p', 'p'), False, False): _init22,
    (('p', 'p', 'p', 'p', 'p', 'p'), True, False): _init23,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p'), False, False): _init24,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init25,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'f', 'p'), False, False): _init26,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'f', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init27,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), False, False): _init28,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init29,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'f', 'f', 'p', 'p'), False, False): _init30,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'f', 'p', 'f'), False, False): _init31,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init32,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), False, False): _init33,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'f', 'p', 'p', 'f', 'f', 'f'), True, False): _init34,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), False, False): _init35,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init36,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), True, False): _init37,
    (('p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p', 'p'), False, False): _init38,
}
