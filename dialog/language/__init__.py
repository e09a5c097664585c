"""What the robot says and reads: the answer grammar, vocabulary, feature tree, questions, descriptions, pictures."""
