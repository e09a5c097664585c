"""Who answers: the teacher protocol, the scripted, oracle and replay teachers, the person at the terminal, and one
question's conversation with any of them."""
