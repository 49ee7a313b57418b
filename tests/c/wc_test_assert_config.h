/* WC_CONFIG_HEADER of test_contracts: routes the library's WC_ASSERT hook to
 * cmocka's mock_assert, so that a violated API contract is observable
 * (expect_assert_failure) instead of a crash. */
#ifndef WC_TEST_ASSERT_CONFIG_H
#define WC_TEST_ASSERT_CONFIG_H

/* cmocka.h declares it the same way; repeated here so the library's
 * translation units need not include cmocka. */
void mock_assert(const int result, const char *const expression, const char *const file, const int line);

#define WC_ASSERT(cond) mock_assert((int)(cond), #cond, __FILE__, __LINE__)

#endif /* WC_TEST_ASSERT_CONFIG_H */
